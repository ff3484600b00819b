// BenchTune.h — `ambience bench --tune`: coordinate descent over the volume's main parameters
// at a fixed capture budget (BenchTune.cpp); writes tune.csv, tuned-volume.json and the best
// settings of each replay on its own.
#pragma once

#include "app/bench/BenchRunner.h"

namespace amb::bench {

void tune(const BenchOptions& o, const Runner& runner, int workers);

}  // namespace amb::bench
