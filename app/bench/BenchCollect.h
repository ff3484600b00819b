// BenchCollect.h — what `ambience bench --collect DIR` reads back from a folder `--emit` wrote,
// and what it trusts of it (no GL, so the readers can be tested and fuzzed alone).
//
// The folder was written by this program but then left to other hands (an engine, a shared
// file system, a person), so each file is read as hostile input: through the size-limited,
// regular-file-only, link-refusing reader (world/TextFile.h), parsed with a depth limit
// (world/JsonText.h), and checked field by field. Nothing named in a file may lead outside the
// folder: replay names are plain file stems, the sweep is the folder's own sweep.json.
//
// [SECTION] Text for one line   hasControlCharacter, printable
// [SECTION] exit-status.txt     ExitStatus, parseExitStatus
// [SECTION] report.json         parseRunReport
// [SECTION] bench.json          BenchManifest, parseBenchManifest, benchManifestJson
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace amb {

// ---- Text for one line -----------------------------------------------------------------------

// True when `text` holds a byte below 0x20 or 0x7f (newline, tab, escape, NUL ...). Such text
// cannot go into an emitted command line (a newline would end the line and start another) or
// into a one-line message.
bool hasControlCharacter(const std::string& text);

// `text` for a one-line message: control characters as \n, \t, \r or \xHH, at most `limit`
// bytes of it (then "...").
std::string printable(const std::string& text, std::size_t limit = 200);

// ---- exit-status.txt -------------------------------------------------------------------------

// Size limits of the files a run folder holds, as --collect reads them.
constexpr std::size_t kMaxExitStatusBytes = 256;
constexpr std::size_t kMaxRunReportBytes = std::size_t(64) << 20;
constexpr std::size_t kMaxBenchManifestBytes = std::size_t(16) << 20;
constexpr std::size_t kLogTailBytes = std::size_t(64) << 10;  // the end of log.txt it reads

struct ExitStatus {
    int code = 0;        // 0-255 as a shell reports it: 128 + n for a run killed by signal n
    double wall_s = -1;  // the run's wall time; -1 when the file does not give it
};

// "<code> <wall seconds>\n" (the seconds may be left out). Throws InputError(where, ...) for
// anything else: a code that is not a whole number 0-255, seconds that are not a finite number
// >= 0, other text.
ExitStatus parseExitStatus(const std::string& text, const std::string& where);

// ---- report.json -----------------------------------------------------------------------------

// A run's report (app/cli/RunReport.h): a JSON object. Throws InputError(where, ...) for
// malformed JSON, a NUL byte, nesting deeper than kMaxJsonDepth, or a top level that is not an
// object. The fields are read with checks of their own (a missing or mistyped one is blank).
nlohmann::json parseRunReport(const std::string& text, const std::string& where);

// ---- bench.json ------------------------------------------------------------------------------

struct BenchManifest {
    struct Replay {
        std::string name, path;  // name: a plain file stem; path: absolute, one line
    };
    std::string command;  // the bench's command line, for the summary
    std::vector<Replay> replays;
    std::string methods, sweep, budgets, oracle, backend;  // sweep: "" or "sweep.json"
    int referenceEvery = 6, fullLengthBudget = 3, screenWitnesses = 0, measureEvery = 10;
    int maxFrames = 0, stride = 2;
    bool frames = false;
    // The reference's light (absent in a bench.json of older code: hemisphere, the only one then).
    std::string referenceLight = "hemisphere";
    double bounceSpacing_m = 256.0, bounceReach_m = 500.0;
    int bounceFace = 32;
    double bounceCanopy_m = 0.0;  // lighting/BounceField.h "Two layers" (0: one layer)
    // What lit the methods' captures (absent in a bench.json of older code: own).
    std::string captureLight = "own";
    std::vector<std::string> runs;  // the run folders, relative: runs/<plain name>
};

// Reads bench.json. Throws InputError(where, ...) for a missing or mistyped key, a replay name
// that is not a plain file stem (letters, digits, '-', '_') or is given twice, a replay path
// that is not absolute or holds a control character, a sweep other than "" or "sweep.json", a
// number out of range, a run folder that is not runs/<plain name>, or any string with a control
// character.
BenchManifest parseBenchManifest(const std::string& text, const std::string& where);

// The JSON --emit writes (parseBenchManifest reads it back unchanged).
nlohmann::json benchManifestJson(const BenchManifest& manifest);

}  // namespace amb
