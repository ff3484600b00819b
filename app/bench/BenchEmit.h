// BenchEmit.h — `ambience bench --emit DIR`: a sweep written out as shell command lines for an
// existing engine (GNU parallel on one machine or over ssh, a Slurm array), to be merged back
// with `ambience bench --collect DIR` (no GL, so the quoting and the files can be tested alone).
//
// [SECTION] Quoting        shellQuote, shellCommand
// [SECTION] One run        EmittedRun, runLine, kExitStatusFile
// [SECTION] The job files  writeJobFiles: commands.txt, jobs.txt, slurm.sh, README.txt
//
// A run folder holds, besides what `ambience run` writes, its settings files, log.txt and
// exit-status.txt: "<exit code> <wall seconds>", written when the run ends, whoever started it
// (a local bench or an emitted line). The collector reads a run from those alone.
#pragma once

#include <string>
#include <vector>

namespace amb {

// ---- Quoting ---------------------------------------------------------------------------------

// `word` as one word of a POSIX shell command, nothing expanded: as is when it holds only
// characters no shell treats specially (letters, digits, and _ - . / : = + , @ %), else in
// single quotes, each ' written as '\''. The empty word is ''.
std::string shellQuote(const std::string& word);

// The words quoted and joined by spaces.
std::string shellCommand(const std::vector<std::string>& args);

// ---- One run ---------------------------------------------------------------------------------

// Written in a run folder when the run has ended: "<exit code> <wall seconds>\n"; a code above
// 128 is a run killed by signal (code - 128), as a shell reports it.
constexpr const char* kExitStatusFile = "exit-status.txt";

struct EmittedRun {
    std::vector<std::string> args;  // `ambience run ...`, absolute paths throughout
    std::string dir;                // the run folder (absolute)
    std::string waitFor;            // a run folder whose exit status comes first ("": none)
};

// One line of POSIX sh that runs `run.args` from any working directory with stdin from
// /dev/null, stdout and stderr into <dir>/log.txt, then writes <dir>/exit-status.txt (through a
// rename, so a waiting line never reads half of it) and exits with the run's code. With
// `waitFor` (and `wait` true) it first waits until <waitFor>/exit-status.txt exists.
std::string runLine(const EmittedRun& run, bool wait);

// ---- The job files ---------------------------------------------------------------------------

// Writes into `dir` (absolute): commands.txt (runLine of each run, no waiting: the first
// `firstStage` lines make the oracles and must end before the others start), jobs.txt (the same
// lines, the later ones waiting for their oracle run: for `parallel --jobs N < jobs.txt`, with
// or without --sshloginfile, and for the Slurm array), slurm.sh (runs line
// $SLURM_ARRAY_TASK_ID of jobs.txt) and README.txt (how to run and collect). `exe` is the
// ambience executable the collect command names. Throws InputError(dir, ...) when a file cannot
// be written.
void writeJobFiles(const std::string& dir, const std::vector<EmittedRun>& runs, int firstStage,
                   const std::string& exe);

}  // namespace amb
