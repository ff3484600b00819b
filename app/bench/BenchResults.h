// BenchResults.h — what `ambience bench` writes of its runs: results.csv (one row a run),
// summary.md (the headline per replay with the ratios and their intervals, stress and memory,
// the budgets, the error budget) and the plots (bench-plots.py).
#pragma once

#include <string>
#include <vector>

#include "app/bench/BenchJobs.h"

namespace amb::bench {

// The number at `path` in `j`, NaN where there is none (a report read back may hold anything).
double number(const json& j, std::initializer_list<const char*> path);

// A CSV field on one line: quoted when it holds a comma or a quote, control characters as spaces.
std::string csvField(const std::string& s);

void writeResultsCsv(const std::vector<Job>& jobs, const std::string& path);

void writeSummary(const std::vector<Job>& jobs, const std::string& path,
                  const std::string& commandLine, const std::string& timing,
                  const std::string& oracle, int idealBudget, int fullLengthBudget);

// The plots of the bench in `out` (bench-plots.py), skipped with a line when matplotlib is missing.
void drawPlots(const std::string& out);

}  // namespace amb::bench
