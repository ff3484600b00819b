// FuzzSupport.h — shared pieces of the libFuzzer targets.
//
// A target feeds one input to one reader. amb::InputError is the reader saying "bad input" and
// is a normal outcome; any other exception escapes to libFuzzer, which reports it (as it does
// crashes, sanitizer reports, timeouts and memory blow-ups).
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace amb::fuzz {

inline std::string asText(const std::uint8_t* data, std::size_t size) {
    return std::string(reinterpret_cast<const char*>(data), size);
}

// A temporary file holding the input, for the readers that take a path. In /dev/shm when it
// exists (no disk traffic at thousands of files a second), else the system's temp directory;
// the name carries the process id so several fuzzers can run side by side. Removed on scope
// exit.
class TempInputFile {
  public:
    TempInputFile(const std::uint8_t* data, std::size_t size, const std::string& extension) {
        namespace fs = std::filesystem;
        std::error_code ec;
        const fs::path dir = fs::is_directory("/dev/shm", ec) ? fs::path("/dev/shm")
                                                              : fs::temp_directory_path();
        path_ = (dir / ("ambience-fuzz-" + std::to_string(::getpid()) + extension)).string();
        std::ofstream out(path_, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
        if (!out) {
            std::fprintf(stderr, "fuzz: cannot write the temporary file %s\n", path_.c_str());
            std::abort();
        }
    }
    ~TempInputFile() { std::remove(path_.c_str()); }
    TempInputFile(const TempInputFile&) = delete;
    TempInputFile& operator=(const TempInputFile&) = delete;
    const std::string& path() const { return path_; }

  private:
    std::string path_;
};

// A property the reader promises for accepted input; a violation is a finding.
#define AMB_FUZZ_EXPECT(cond)                                                          \
    do {                                                                               \
        if (!(cond)) {                                                                 \
            std::fprintf(stderr, "fuzz: %s:%d: violated: %s\n", __FILE__, __LINE__, #cond); \
            std::abort();                                                              \
        }                                                                              \
    } while (0)

}  // namespace amb::fuzz
