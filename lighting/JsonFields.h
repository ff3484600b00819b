// JsonFields.h — reads the keys of one JSON object into settings fields: each key is checked for
// type and range, and a key no field claims is an error (a misspelt setting must not be ignored
// silently). Errors are InputError(where, ...) naming the key.
#pragma once

#include <algorithm>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "world/Error.h"

namespace amb {

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
        throw InputError(where_, std::string("'") + key + "' must be in [" + std::to_string(lo) +
                                     ", " + std::to_string(hi) + "]");
    }
    const nlohmann::json& object_;
    std::string where_;
    std::vector<std::string> known_;
};

}  // namespace amb
