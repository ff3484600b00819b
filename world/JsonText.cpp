// JsonText.cpp — see JsonText.h.
#include "world/JsonText.h"

#include "world/Error.h"

namespace amb {

nlohmann::json parseJsonText(const std::string& text, const std::string& where, int maxDepth) {
    const std::size_t nul = text.find('\0');
    if (nul != std::string::npos)
        throw InputError(
            where, "a NUL byte at offset " + std::to_string(nul) + " (a JSON text holds none)");
    // The parser reports the depth of each value as it reads it; refuse as soon as one is too
    // deep, before the rest of a hostile file is read.
    const nlohmann::json::parser_callback_t limitDepth = [&](int depth,
                                                             nlohmann::json::parse_event_t,
                                                             nlohmann::json&) {
        // `depth` counts the containers around a value, so maxDepth levels of objects or
        // arrays holding values read, and one more does not.
        if (depth > maxDepth)
            throw InputError(where, "nested deeper than " + std::to_string(maxDepth) + " levels");
        return true;
    };
    return nlohmann::json::parse(text, limitDepth);
}

}  // namespace amb
