// JsonText.h — the one way the readers of user files parse JSON text. nlohmann's parser takes a
// NUL byte as the end of its input, so "{...}\0anything" would pass as "{...}"; and copying,
// comparing or printing a json value recurses once per level, so a file nested a million levels
// deep parses (the parser itself does not recurse) and then overflows the stack. Both are
// refused here, before any reader sees the value.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace amb {

// Deepest nesting of objects and arrays a user file may have. Every file the program reads is
// a few levels deep (a run report, the deepest, is about six).
constexpr int kMaxJsonDepth = 64;

// Parses `text` as JSON. Throws InputError(where, ...) for a NUL byte (naming its offset) or
// nesting deeper than `maxDepth`; syntax errors and numbers out of range are thrown as the
// library's own exceptions (nlohmann::json::exception), which each reader words for its file.
nlohmann::json parseJsonText(const std::string& text, const std::string& where,
                             int maxDepth = kMaxJsonDepth);

}  // namespace amb
