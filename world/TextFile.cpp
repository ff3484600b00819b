// TextFile.cpp — bounded whole-file reads (see TextFile.h).
#include "world/TextFile.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "world/Error.h"

namespace amb {

namespace {

// An open file descriptor, closed on scope exit.
class Fd {
  public:
    explicit Fd(int fd) : fd_(fd) {}
    ~Fd() {
        if (fd_ >= 0) ::close(fd_);
    }
    Fd(const Fd&) = delete;
    Fd& operator=(const Fd&) = delete;
    int get() const { return fd_; }

  private:
    int fd_;
};

// Opens `path` for reading and checks it is a regular file; returns its size. O_NONBLOCK keeps
// the open of a FIFO from waiting for a writer; the checks are made on the opened file, so the
// path cannot be swapped between a check and the read.
int openRegular(const std::string& path, const char* what, Links links, std::size_t& size) {
    int flags = O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY;
    if (links == Links::Refuse) flags |= O_NOFOLLOW;
    const int fd = ::open(path.c_str(), flags);
    if (fd < 0) {
        if (errno == ELOOP && links == Links::Refuse)
            throw InputError(path, std::string("the ") + what +
                                       " is a symbolic link (refused: it could point anywhere)");
        throw InputError(path, std::string("cannot open the ") + what + " (" +
                                   std::strerror(errno) + ")");
    }
    struct stat st {};
    if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        ::close(fd);
        throw InputError(path, std::string("the ") + what + " is not a regular file");
    }
    // Regular files never block; reads go back to blocking mode for clarity.
    ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);
    size = std::size_t(st.st_size);
    return fd;
}

// Appends up to `limit` + 1 bytes read from `fd` to `text` (the + 1 tells a file that grew).
void readUpTo(int fd, const std::string& path, const char* what, std::size_t limit,
              std::string& text) {
    char buffer[1 << 16];
    while (text.size() <= limit) {
        const ssize_t n = ::read(fd, buffer, sizeof buffer);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) throw InputError(path, std::string("read error in the ") + what);
        if (n == 0) break;
        text.append(buffer, std::size_t(n));
    }
}

}  // namespace

std::string readTextFile(const std::string& path, const char* what, std::size_t maxBytes,
                         Links links) {
    std::size_t size = 0;
    const Fd fd(openRegular(path, what, links, size));
    if (size > maxBytes) {
        throw InputError(path, std::string("the ") + what + " is too large (" +
                                   std::to_string(size) + " bytes, at most " +
                                   std::to_string(maxBytes) + ")");
    }
    std::string text;
    text.reserve(size);
    readUpTo(fd.get(), path, what, maxBytes, text);
    if (text.size() > maxBytes) {
        throw InputError(path, std::string("the ") + what + " is too large (more than " +
                                   std::to_string(maxBytes) + " bytes)");
    }
    return text;
}

std::string readTextFileTail(const std::string& path, const char* what, std::size_t maxBytes,
                             Links links) {
    std::size_t size = 0;
    const Fd fd(openRegular(path, what, links, size));
    if (size > maxBytes && ::lseek(fd.get(), off_t(size - maxBytes), SEEK_SET) < 0)
        throw InputError(path, std::string("read error in the ") + what);
    std::string text;
    readUpTo(fd.get(), path, what, maxBytes, text);
    if (text.size() > maxBytes) text.erase(0, text.size() - maxBytes);
    return text;
}

void writeTextFile(const std::string& path, const std::string& text, const char* what,
                   unsigned mode) {
    const std::string pending = path + ".tmp" + std::to_string(::getpid());
    const auto fail = [&](const char* doing) {
        const std::string reason = std::strerror(errno);
        ::unlink(pending.c_str());
        throw InputError(path, std::string("cannot ") + doing + " the " + what + " (" + reason +
                                   ")");
    };
    ::unlink(pending.c_str());  // one left by a process of this id that was killed
    const int fd =
        ::open(pending.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, mode);
    if (fd < 0) fail("write");
    std::size_t done = 0;
    while (done < text.size()) {
        const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
            ::close(fd);
            fail("write");
        }
        done += std::size_t(n);
    }
    if (::close(fd) != 0) fail("write");
    if (::rename(pending.c_str(), path.c_str()) != 0) fail("replace");
}

}  // namespace amb
