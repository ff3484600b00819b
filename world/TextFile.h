// TextFile.h — reading a whole input file with a size limit. Every reader of user files goes
// through here, so a device (/dev/zero), a pipe or a huge file is refused with an InputError
// naming the path instead of filling memory or blocking.
#pragma once

#include <cstddef>
#include <string>

namespace amb {

// Default limits, in bytes, by kind of input.
constexpr std::size_t kMaxSettingsFileBytes = std::size_t(16) << 20;  // JSON settings, sweeps
constexpr std::size_t kMaxReplayFileBytes = std::size_t(128) << 20;   // replays (~1M samples)
constexpr std::size_t kMaxOracleFileBytes = std::size_t(256) << 20;   // oracle caches

// Whether a symbolic link is followed. Files a program wrote into a folder of its own (a
// bench's run folders) are read with Links::Refuse, so a link planted there cannot make it
// read a file outside the folder.
enum class Links { Follow, Refuse };

// Reads `path` whole. Throws InputError(path, ...) when it cannot be opened, is not a regular
// file (a pipe or a device is refused without blocking on it), is a symbolic link and `links`
// is Refuse, is larger than `maxBytes`, or a read fails. `what` names the kind of file in
// messages ("replay file", "ambience settings file").
std::string readTextFile(const std::string& path, const char* what, std::size_t maxBytes,
                         Links links = Links::Follow);

// The last `maxBytes` bytes of the regular file `path` (all of it when shorter), with the same
// checks as readTextFile but no size limit on the file itself: for logs, whose end is what
// matters.
std::string readTextFileTail(const std::string& path, const char* what, std::size_t maxBytes,
                             Links links = Links::Follow);

// Writes `text` as the file `path`: into a new file beside it (created, never opened through a
// link), then renamed over `path`. A symbolic link at `path` is replaced by the file, not
// written through, and a reader never sees half of it. Throws InputError(path, ...) when the
// file cannot be written (its folder missing or read-only, `path` a folder).
void writeTextFile(const std::string& path, const std::string& text, const char* what,
                   unsigned mode = 0644);

}  // namespace amb
