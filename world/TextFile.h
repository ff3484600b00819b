// TextFile.h — reading a whole input file with a size limit. Every reader of user files goes
// through here, so a device (/dev/zero), a pipe or a huge file is refused with an InputError
// naming the path instead of filling memory.
#pragma once

#include <cstddef>
#include <string>

namespace amb {

// Default limits, in bytes, by kind of input.
constexpr std::size_t kMaxSettingsFileBytes = std::size_t(16) << 20;  // JSON settings, sweeps
constexpr std::size_t kMaxReplayFileBytes = std::size_t(128) << 20;   // replays (~1M samples)
constexpr std::size_t kMaxOracleFileBytes = std::size_t(256) << 20;   // oracle caches

// Reads `path` whole. Throws InputError(path, ...) when it cannot be opened, is not a regular
// file, is larger than `maxBytes`, or a read fails. `what` names the kind of file in messages
// ("replay file", "ambience settings file").
std::string readTextFile(const std::string& path, const char* what, std::size_t maxBytes);

}  // namespace amb
