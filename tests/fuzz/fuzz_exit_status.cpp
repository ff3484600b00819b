// fuzz_exit_status — a run's exit-status.txt as `ambience bench --collect` reads it (a bounded,
// link-refusing read, then amb::parseExitStatus, app/bench/BenchCollect.h). An accepted status
// is a shell's exit code (0-255) and a wall time that is finite and not negative (or -1: not
// given).
#include <cmath>

#include "FuzzSupport.h"
#include "app/bench/BenchCollect.h"
#include "world/Error.h"
#include "world/TextFile.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const amb::fuzz::TempInputFile file(data, size, ".txt");
    amb::ExitStatus status;
    try {
        status =
            amb::parseExitStatus(amb::readTextFile(file.path(), "exit status file",
                                                   amb::kMaxExitStatusBytes, amb::Links::Refuse),
                                 file.path());
    } catch (const amb::InputError&) {
        return 0;
    }
    AMB_FUZZ_EXPECT(status.code >= 0 && status.code <= 255);
    AMB_FUZZ_EXPECT(std::isfinite(status.wall_s));
    AMB_FUZZ_EXPECT(status.wall_s >= 0.0 || status.wall_s == -1.0);
    return 0;
}
