// Error.h — the two error channels (docs/ARCHITECTURE.md "Style").
//   InputError: bad input from a user or a file. Says where (file, field, sample index) and what
//               was expected. The CLI prints it on one line and exits with code 2.
//   AMB_CHECK:  a programmer error; prints the failed condition and aborts.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace amb {

class InputError : public std::runtime_error {
public:
    // `where` names the input (file path, option, "field 'x' of sample 12"); `what` the problem.
    InputError(const std::string& where, const std::string& what)
        : std::runtime_error(where.empty() ? what : where + ": " + what) {}
};

// A command whose own work failed (not its input, not a bug): one line, exit code 1.
class RunFailure : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

}  // namespace amb

#define AMB_CHECK(cond)                                                                    \
    do {                                                                                   \
        if (!(cond)) {                                                                     \
            std::fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond); \
            std::abort();                                                                  \
        }                                                                                  \
    } while (0)
