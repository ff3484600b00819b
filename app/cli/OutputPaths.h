// OutputPaths.h — checks on a command's files before any work is done:
//   * an output never overwrites an input or another output (compared after resolving "..",
//     symbolic links and hard links);
//   * every output can be written (its folder exists and is writable, and the file, if it
//     exists, is a writable regular file), so a run does not fail after its work is done;
//   * names that come from files (a replay's "name") become safe file-name stems, so a replay
//     cannot steer where a run writes.
#pragma once

#include <string>
#include <vector>

namespace amb {

// `name` reduced to letters, digits, '-' and '_' (each run of other characters, dots and
// slashes included, becomes one '_'), at most 64 characters; "replay" when nothing is left.
// It is one plain path component: never "..", never a '/', never a hidden file.
std::string safeFileStem(const std::string& name);

class FilePlan {
  public:
    // `option` names the file in messages ("--replay", "--report"). Empty paths are ignored.
    void input(const std::string& option, const std::string& path);
    void output(const std::string& option, const std::string& path);
    // An output written through world/TextFile.h writeTextFile: a symbolic link at `path` is
    // replaced by the file, so the link is the output, not what it points to.
    void replacedOutput(const std::string& option, const std::string& path);
    // Throws InputError naming the option when an output equals an input or another output,
    // or cannot be written.
    void check() const;

  private:
    struct Entry {
        std::string option, path, resolved;
        bool replacesLink = false;
    };
    std::vector<Entry> inputs_, outputs_;
};

// The absolute, normalised form of `path` (existing parts with symbolic links resolved).
std::string resolvedPath(const std::string& path);

}  // namespace amb
