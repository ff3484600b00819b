// fuzz_run_report — a run's report.json as `ambience bench --collect` reads it (a bounded,
// link-refusing read, then amb::parseRunReport, app/bench/BenchCollect.h). An accepted report is
// an object no deeper than the limit, so the collector may copy, compare and print it (each of
// which recurses) without running out of stack.
#include "FuzzSupport.h"
#include "app/bench/BenchCollect.h"
#include "world/Error.h"
#include "world/TextFile.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const amb::fuzz::TempInputFile file(data, size, ".json");
    nlohmann::json report;
    try {
        report = amb::parseRunReport(amb::readTextFile(file.path(), "run report",
                                                       amb::kMaxRunReportBytes, amb::Links::Refuse),
                                     file.path());
    } catch (const amb::InputError&) {
        return 0;
    }
    AMB_FUZZ_EXPECT(report.is_object());
    // What the collector does with it: copies (the rows and tables take parts by value) and
    // prints (a failed row's message); neither may throw or overflow.
    const nlohmann::json copy = report;
    AMB_FUZZ_EXPECT(copy == report);
    (void)report.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
    return 0;
}
