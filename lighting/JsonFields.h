// JsonFields.h — reads the keys of one JSON object into settings fields: each key is checked for
// type and range, and a key no field claims is an error (a misspelt setting must not be ignored
// silently). Errors are InputError(where, ...) naming the key; readJsonSettings() parses the
// text and turns any exception of the JSON library into an InputError too, so a settings reader
// built on it throws nothing else on any input text.
#pragma once

#include <algorithm>
#include <climits>
#include <cstdio>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "world/Error.h"
#include "world/JsonText.h"

namespace amb {

// A number for messages: up to 6 significant digits ("0.05", "1e+06", "inf").
inline std::string jsonNumber(double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%.6g", v);
    return text;
}

class JsonFields {
  public:
    JsonFields(const nlohmann::json& object, std::string where)
        : object_(object), where_(std::move(where)) {
        if (!object_.is_object()) throw InputError(where_, "expected a JSON object");
    }
    void number(const char* key, double& field, double lo, double hi) {
        known_.push_back(key);
        if (!object_.contains(key)) return;
        const auto& v = object_.at(key);
        if (!v.is_number()) throw InputError(where_, std::string("'") + key + "' must be a number");
        const double x = v.get<double>();
        if (!(x >= lo && x <= hi)) outOfRange(key, lo, hi);
        field = x;
    }
    void integer(const char* key, int& field, int lo, int hi) {
        known_.push_back(key);
        if (!object_.contains(key)) return;
        const auto& v = object_.at(key);
        if (!v.is_number_integer()) {
            throw InputError(where_, std::string("'") + key + "' must be an integer");
        }
        // An unsigned value above LLONG_MAX would wrap negative as a long long.
        if (v.is_number_unsigned() && v.get<unsigned long long>() > (unsigned long long)LLONG_MAX)
            outOfRange(key, lo, hi);
        const long long x = v.get<long long>();
        if (x < lo || x > hi) outOfRange(key, lo, hi);
        field = int(x);
    }
    void boolean(const char* key, bool& field) {
        known_.push_back(key);
        if (!object_.contains(key)) return;
        const auto& v = object_.at(key);
        if (!v.is_boolean())
            throw InputError(where_, std::string("'") + key + "' must be true or false");
        field = v.get<bool>();
    }
    void object(const char* key, const std::function<void(JsonFields&)>& read) {
        known_.push_back(key);
        if (!object_.contains(key)) return;
        JsonFields inner(object_.at(key), where_ + ": '" + key + "'");
        read(inner);
        inner.finish();
    }
    void finish() const {
        for (auto it = object_.begin(); it != object_.end(); ++it) {
            if (std::find(known_.begin(), known_.end(), it.key()) == known_.end()) {
                throw InputError(where_, "unknown key '" + it.key() + "'");
            }
        }
    }

  private:
    [[noreturn]] void outOfRange(const char* key, double lo, double hi) const {
        throw InputError(where_, std::string("'") + key + "' must be in [" + jsonNumber(lo) + ", " +
                                     jsonNumber(hi) + "]");
    }
    const nlohmann::json& object_;
    std::string where_;
    std::vector<std::string> known_;
};

// Parses `jsonText` and lets `read` take the root object's fields, then rejects unknown keys.
// Anything the JSON library throws (syntax, numbers out of double range, type errors) becomes
// InputError(where, ...).
inline void readJsonSettings(const std::string& jsonText, const std::string& where,
                             const std::function<void(JsonFields&)>& read) {
    try {
        const nlohmann::json root = parseJsonText(jsonText, where);
        JsonFields fields(root, where);
        read(fields);
        fields.finish();
    } catch (const nlohmann::json::exception& e) {
        throw InputError(where, std::string("not valid settings JSON: ") + e.what());
    }
}

}  // namespace amb
