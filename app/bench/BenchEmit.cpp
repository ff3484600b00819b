// BenchEmit.cpp — the command lines and job files of `ambience bench --emit` (see BenchEmit.h).
#include "app/bench/BenchEmit.h"

#include <filesystem>

#include "app/bench/BenchCollect.h"
#include "world/Error.h"
#include "world/TextFile.h"

namespace amb {

namespace {

namespace fs = std::filesystem;

std::string inDir(const std::string& dir, const std::string& file) {
    return (fs::path(dir) / file).string();
}

void writeFile(const std::string& path, const std::string& text, unsigned mode = 0644) {
    writeTextFile(path, text, "job file", mode);
}

// The texts read as they will be printed (clang-format would break them at every "+").
// clang-format off
std::string readmeText(const std::string& dir, std::size_t runs, int firstStage,
                       const std::string& exe) {
    const std::string d = shellQuote(dir), n = std::to_string(runs),
                      last = std::to_string(runs ? runs - 1 : 0),
                      stage = std::to_string(firstStage),
                      jobs = shellQuote(inDir(dir, "jobs.txt")),
                      slurm = shellQuote(inDir(dir, "slurm.sh"));
    return "ambience bench, emitted: " + n + " runs, each one line of POSIX sh.\n"
           "\n"
           "Every path in the lines is absolute (the executable, the replays, each run's settings\n"
           "and output), so a line runs from any working directory, and on another machine that\n"
           "has the same paths (the same build, and this folder on a shared file system).\n"
           "\n"
           "Files\n"
           "  commands.txt  one line per run. The first " + stage + " line(s) capture and save the\n"
           "                oracles (one run per replay, oracle/<replay>.json); the others read\n"
           "                them, so run the first " + stage + " before the rest (an engine with\n"
           "                dependencies of its own: those " + stage + " first, then the rest).\n"
           "  jobs.txt      the same lines, each later one first waiting (sleep 2 s, then look\n"
           "                again) until its replay's oracle run has written exit-status.txt; the\n"
           "                oracle runs come first, so an engine that starts lines in order never\n"
           "                waits for a line it has not started.\n"
           "  slurm.sh      a Slurm array job: task i runs line i + 1 of jobs.txt.\n"
           "  bench.json    the sweep, for the collector; sweep.json: a copy of --sweep.\n"
           "  runs/<replay>__<method>__<point>/  each run's settings; the run writes its\n"
           "                report, log.txt and exit-status.txt (\"<exit code> <seconds>\") here.\n"
           "\n"
           "Run on this machine with GNU parallel (N runs side by side):\n"
           "  parallel --will-cite --jobs N < " + jobs + "\n"
           "\n"
           "Run over machines (one per line of hosts.txt, \":\" for this one; every machine sees\n"
           "this folder at the same path):\n"
           "  parallel --will-cite --jobs N --sshloginfile hosts.txt < " + jobs + "\n"
           "\n"
           "The lines are POSIX sh: if your login shell is csh or fish, set PARALLEL_SHELL=/bin/sh.\n"
           "parallel exits with the number of failed runs; they are recorded, and collected.\n"
           "\n"
           "Run on Slurm, all at once (tasks wait for their oracle run):\n"
           "  sbatch --array=0-" + last + " " + slurm + "\n"
           "or in two stages (nothing waits):\n"
           "  jid=$(sbatch --parsable --array=0-" + std::to_string(firstStage - 1) + " " + slurm +
           ")\n"
           "  sbatch --dependency=afterany:$jid --array=" + stage + "-" + last + " " + slurm + "\n"
           "\n"
           "Collect (results.csv, summary.md and the plots, as a local bench writes them; a run\n"
           "that failed or never ran is reported as failed with its error):\n"
           "  " + shellQuote(exe) + " bench --collect " + d + "\n"
           "\n"
           "A run that failed can be run again by its line; collect again afterwards. To run\n"
           "jobs.txt again as a whole, emit again first: that clears the exit status files the\n"
           "waiting lines look at.\n";
}

std::string slurmScript(const std::string& dir, std::size_t runs) {
    const std::string jobs = shellQuote(inDir(dir, "jobs.txt"));
    const std::string last = std::to_string(runs ? runs - 1 : 0);
    return "#!/bin/sh\n"
           "# ambience bench, emitted: " + std::to_string(runs) + " runs. Submit with\n"
           "#   sbatch --array=0-" + last + " " + shellQuote(inDir(dir, "slurm.sh")) + "\n"
           "# Task i runs line i + 1 of jobs.txt (README.txt beside it says more).\n"
           "#SBATCH --job-name=ambience-bench\n"
           "#SBATCH --ntasks=1\n"
           "#SBATCH --cpus-per-task=1\n"
           "set -eu\n"
           ": \"${SLURM_ARRAY_TASK_ID:?submit as an array job: sbatch --array=0-" + last +
           " slurm.sh}\"\n"
           "line=$(sed -n \"$((SLURM_ARRAY_TASK_ID + 1))p\" " + jobs + ")\n"
           "if [ -z \"$line\" ]; then\n"
           "    echo \"slurm.sh: no line $((SLURM_ARRAY_TASK_ID + 1)) in \"" + jobs + " >&2\n"
           "    exit 2\n"
           "fi\n"
           "exec /bin/sh -c \"$line\"\n";
}

// clang-format on

}  // namespace

// ---- Quoting ---------------------------------------------------------------------------------

std::string shellQuote(const std::string& word) {
    bool plain = !word.empty();
    for (const char c : word) {
        const bool safe = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
                          (c >= '0' && c <= '9') ||
                          std::string("_-./:=+,@%").find(c) != std::string::npos;
        if (!safe) plain = false;
    }
    if (plain) return word;
    std::string q = "'";
    for (const char c : word) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

std::string shellCommand(const std::vector<std::string>& args) {
    std::string line;
    for (const std::string& a : args) line += (line.empty() ? "" : " ") + shellQuote(a);
    return line;
}

// ---- One run ---------------------------------------------------------------------------------

std::string runLine(const EmittedRun& run, bool wait) {
    const std::string status = shellQuote(inDir(run.dir, kExitStatusFile));
    const std::string pending = shellQuote(inDir(run.dir, std::string(kExitStatusFile) + ".tmp"));
    std::string line;
    if (wait && !run.waitFor.empty())
        line += "while [ ! -e " + shellQuote(inDir(run.waitFor, kExitStatusFile)) +
                " ]; do sleep 2; done; ";
    // No exit status from an earlier attempt while this one runs; the wall time in whole
    // seconds (`date +%s`: GNU, BSD and busybox all have it).
    line += "rm -f " + status + "; t0=$(date +%s); " + shellCommand(run.args) + " >" +
            shellQuote(inDir(run.dir, "log.txt")) + " 2>&1 </dev/null; s=$?; echo \"$s " +
            "$(($(date +%s) - t0))\" >" + pending + " && mv -f " + pending + " " + status +
            "; exit $s";
    return line;
}

// ---- The job files ---------------------------------------------------------------------------

void writeJobFiles(const std::string& dir, const std::vector<EmittedRun>& runs, int firstStage,
                   const std::string& exe) {
    std::string commands, jobs;
    for (const EmittedRun& r : runs) {
        // Each run is one line: a newline in any word would end it and start another command.
        std::vector<std::string> words = r.args;
        words.insert(words.end(), {r.dir, r.waitFor, exe});
        for (const std::string& w : words)
            if (hasControlCharacter(w))
                throw InputError(dir, "a run's command line would hold a control character, in '" +
                                          printable(w) + "': refusing to emit it");
        commands += runLine(r, false) + "\n";
        jobs += runLine(r, true) + "\n";
    }
    writeFile(inDir(dir, "commands.txt"), commands);
    writeFile(inDir(dir, "jobs.txt"), jobs);
    const std::string slurm = inDir(dir, "slurm.sh");
    writeFile(slurm, slurmScript(dir, runs.size()), 0755);
    writeFile(inDir(dir, "README.txt"), readmeText(dir, runs.size(), firstStage, exe));
}

}  // namespace amb
