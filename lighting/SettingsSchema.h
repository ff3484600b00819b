// SettingsSchema.h — every key of the two settings files, described once. The volume's file
// (AmbienceVolumeSettings: `ambience run --config`, `"volume"` in a sweep point) and the
// baselines' (BaselineSettings: `--baseline-config`, `"baseline"`) each have a schema: for each
// key its path in the file ("store.blendTime_s", "facesPerFrame", "nearField.radius_m"), kind,
// unit, range, whether a slider for it moves in ratios, a one-line help, whether a change
// rebuilds the method, and which end of its range costs frame time. Everything else is driven
// from it:
//   - the readers (ambienceSettingsFromJson, baselineSettingsFromJson) walk the schema: each key
//     checked for type and range, an unknown key an error naming it, then the checks that bind
//     keys together (lifetimes, the finest spacing, the objects' range);
//   - the writer (write): every key, nested as the reader expects;
//   - equality (equal) and what may change in a running volume (sameWhereRebuilding, which is
//     AmbienceVolume::retunable);
//   - `KEY=VALUE` assignments (assign), through the same checks;
//   - the key tables (Markdown), the fuzz dictionary, and the worst case of the ranges.
//
// [SECTION] The schema     SettingSpec, SettingField, SettingsSchema<S>
// [SECTION] The two files  volumeSettingsSchema(), baselineSettingsSchema()
// [SECTION] Generated text the key tables (Markdown) and the fuzz dictionary
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "lighting/AmbienceVolume.h"
#include "lighting/Baselines.h"

namespace amb {

// ---- [SECTION] The schema ----------------------------------------------------------------------

// What the schema says about one key.
struct SettingSpec {
    enum class Kind { Number, Integer, Boolean };
    // The end of the range that costs frame time (or memory), if either does.
    enum class Cost { None, AtHigh, AtLow };

    std::string key;  // its path in the settings file: "store.blendTime_s", "facesPerFrame"
    Kind kind = Kind::Number;
    std::string unit;           // "m", "s", "rad", ...; "" for counts, ratios and switches
    double lo = 0.0, hi = 1.0;  // the range the reader accepts (switches: 0 and 1)
    bool logarithmic = false;   // a slider for it moves in ratios
    std::string help;           // one line
    // A change cannot apply to a running volume (AmbienceVolume::retunable): the lattice, the
    // sun threshold and the near field, which the volume is built with.
    bool rebuilds = false;
    Cost cost = Cost::None;
    // The end of the range that costs (switches: on); lo or hi when neither does.
    double worstValue() const { return cost == Cost::AtLow ? lo : hi; }
};

// A key of the settings struct S: its spec and the field it sets.
template <typename S>
struct SettingField : SettingSpec {
    std::function<void*(S&)> field;  // the double, int or bool, as `kind` says
};

template <typename S>
class SettingsSchema {
  public:
    using Field = SettingField<S>;
    // The checks that bind keys together; throw InputError(where, ...).
    using Check = std::function<void(const S&, const std::string& where)>;

    SettingsSchema(std::vector<Field> fields, Check check);

    // Every key, in the file's order.
    const std::vector<Field>& fields() const { return fields_; }
    const Field* find(const std::string& key) const;

    // A key's value as a double (switches 0 or 1), and set from one (integers rounded,
    // switches on when not 0). No range check.
    static double value(const S& settings, const Field& field);
    static void setValue(S& settings, const Field& field, double value);

    // Settings from JSON text: an object of the keys (nested objects for "store.", ...); missing
    // keys keep their defaults. Unknown keys, wrong types, values out of range and the checks
    // that bind keys together throw InputError(where, ...) naming the key; so does anything the
    // JSON library throws.
    S read(const std::string& jsonText, const std::string& where) const;
    // Every key, nested as read() expects: read(write(s)) == s.
    std::string write(const S& settings) const;
    // The checks that bind keys together (read() runs them).
    void check(const S& settings, const std::string& where) const { check_(settings, where); }

    // Every key equal.
    bool equal(const S& a, const S& b) const;
    // Every key that rebuilds the method equal (the others may differ).
    bool sameWhereRebuilding(const S& a, const S& b) const;

    // `KEY=VALUE` (VALUE as in the file: a number, an integer, true or false) into `settings`,
    // with the reader's type and range checks; InputError(where, ...) naming the key otherwise.
    // The checks that bind keys together are left to check().
    void assign(S& settings, const std::string& assignment, const std::string& where) const;
    // The same when KEY is one of this schema's; false (nothing changed) otherwise.
    bool assignIfKnown(S& settings, const std::string& assignment, const std::string& where) const;

    // The defaults with each costly key at its costly end (switches with a cost: on).
    S worstCase() const;

  private:
    std::vector<Field> fields_;
    Check check_;
};

// ---- [SECTION] The two files -------------------------------------------------------------------

const SettingsSchema<AmbienceVolumeSettings>& volumeSettingsSchema();
const SettingsSchema<BaselineSettings>& baselineSettingsSchema();

// The key of `KEY=VALUE` (all of it when there is no '=').
std::string assignmentKey(const std::string& assignment);

// ---- [SECTION] Generated text ------------------------------------------------------------------

// The key tables of docs/TUNING.md (between its "settings-schema" markers): one Markdown table
// per settings file, a row per key.
std::string settingsMarkdown();
// The settings part of the fuzz dictionary tests/fuzz/json.dict: every name a settings file
// may hold (keys and the objects they sit in), once, sorted.
std::string settingsFuzzDictionary();

}  // namespace amb
