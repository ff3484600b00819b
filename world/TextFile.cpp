// TextFile.cpp — bounded whole-file reads (see TextFile.h).
#include "world/TextFile.h"

#include <sys/stat.h>

#include <fstream>
#include <iterator>

#include "world/Error.h"

namespace amb {

std::string readTextFile(const std::string& path, const char* what, std::size_t maxBytes) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) throw InputError(path, std::string("cannot open the ") + what);
    if (!S_ISREG(st.st_mode))
        throw InputError(path, std::string("the ") + what + " is not a regular file");
    if (std::size_t(st.st_size) > maxBytes) {
        throw InputError(path, std::string("the ") + what + " is too large (" +
                                   std::to_string(st.st_size) + " bytes, at most " +
                                   std::to_string(maxBytes) + ")");
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path, std::string("cannot open the ") + what);
    std::string text;
    text.reserve(std::size_t(st.st_size));
    // Read at most maxBytes + 1 bytes, in case the file grew after stat().
    char buffer[1 << 16];
    while (in) {
        in.read(buffer, sizeof(buffer));
        text.append(buffer, std::size_t(in.gcount()));
        if (text.size() > maxBytes) {
            throw InputError(path, std::string("the ") + what + " is too large (more than " +
                                       std::to_string(maxBytes) + " bytes)");
        }
    }
    if (in.bad()) throw InputError(path, std::string("read error in the ") + what);
    return text;
}

}  // namespace amb
