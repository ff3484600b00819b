// OutputPaths.cpp — see OutputPaths.h.
#include "app/cli/OutputPaths.h"

#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>

#include "world/Error.h"

namespace amb {

namespace fs = std::filesystem;

std::string safeFileStem(const std::string& name) {
    std::string out;
    bool gap = false;
    for (const char c : name) {
        const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                        c == '-' || c == '_';
        if (ok) {
            if (gap && !out.empty()) out += '_';
            gap = false;
            out += c;
        } else {
            gap = true;  // '/', '.', quotes, spaces, control characters ...
        }
        if (out.size() >= 64) break;
    }
    return out.empty() ? "replay" : out;
}

std::string resolvedPath(const std::string& path) {
    std::error_code ec;
    fs::path p = fs::weakly_canonical(fs::absolute(path, ec), ec);
    if (ec) p = fs::absolute(path).lexically_normal();
    return p.string();
}

namespace {

bool sameFile(const std::string& a, const std::string& resolvedA, const std::string& b,
              const std::string& resolvedB, bool linkA = false) {
    if (resolvedA == resolvedB) return true;
    if (linkA) return false;  // the link itself is replaced: what it points to is not written
    struct stat sa {}, sb {};
    return ::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0 && sa.st_dev == sb.st_dev &&
           sa.st_ino == sb.st_ino;
}

bool isLink(const std::string& path) {
    struct stat st {};
    return ::lstat(path.c_str(), &st) == 0 && S_ISLNK(st.st_mode);
}

void checkWritable(const std::string& option, const std::string& path, bool replacesLink) {
    struct stat st {};
    if (!(replacesLink && isLink(path)) && ::stat(path.c_str(), &st) == 0) {
        if (!S_ISREG(st.st_mode))
            throw InputError(option, "'" + path + "' exists and is not a regular file");
        if (::access(path.c_str(), W_OK) != 0)
            throw InputError(option, "'" + path + "' is not writable");
        return;
    }
    fs::path parent = fs::path(path).parent_path();
    if (parent.empty()) parent = ".";
    if (::stat(parent.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
        throw InputError(option, "the folder of '" + path + "' does not exist");
    if (::access(parent.c_str(), W_OK | X_OK) != 0)
        throw InputError(option, "the folder of '" + path + "' is not writable");
}

}  // namespace

void FilePlan::input(const std::string& option, const std::string& path) {
    if (!path.empty()) inputs_.push_back({option, path, resolvedPath(path)});
}

void FilePlan::output(const std::string& option, const std::string& path) {
    if (!path.empty()) outputs_.push_back({option, path, resolvedPath(path)});
}

void FilePlan::replacedOutput(const std::string& option, const std::string& path) {
    if (path.empty()) return;
    if (!isLink(path)) return output(option, path);
    const fs::path p(path);
    const std::string parent = p.parent_path().empty() ? "." : p.parent_path().string();
    outputs_.push_back(
        {option, path, (fs::path(resolvedPath(parent)) / p.filename()).string(), true});
}

void FilePlan::check() const {
    for (std::size_t i = 0; i < outputs_.size(); ++i) {
        const Entry& o = outputs_[i];
        for (const Entry& in : inputs_) {
            if (sameFile(o.path, o.resolved, in.path, in.resolved, o.replacesLink))
                throw InputError(o.option, "'" + o.path + "' is also the input " + in.option +
                                               ": refusing to overwrite it");
        }
        for (std::size_t j = 0; j < i; ++j) {
            const Entry& other = outputs_[j];
            if (sameFile(o.path, o.resolved, other.path, other.resolved,
                         o.replacesLink || other.replacesLink))
                throw InputError(o.option,
                                 "'" + o.path + "' is also the output " + other.option);
        }
    }
    for (const Entry& o : outputs_) checkWritable(o.option, o.path, o.replacesLink);
}

}  // namespace amb
