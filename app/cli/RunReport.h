// RunReport.h — what `ambience run` (and `view`) share: image size parsing, the ffmpeg video
// pipe, the progress bar, and the report (JSON with timing statistics, per-frame rows, CSV).
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "app/frame/FrameLoop.h"

namespace amb {

struct Size {
    int width = 0, height = 0;
};
// "WxH" with 1 <= W, H <= 16384; throws InputError naming `where`.
Size parseSize(const std::string& text, const std::string& where);

// Writes top-down 8-bit RGB as an image (format from the extension) with OpenImageIO.
void writeImageRgb8(const std::string& path, int width, int height,
                    const std::vector<unsigned char>& rgb);

// Raw RGB frames piped to the ffmpeg command-line tool (H.264 in MP4), started with an argument
// vector (no shell). Throws InputError with a clear message when ffmpeg is not installed.
class VideoPipe {
  public:
    VideoPipe(const std::string& path, int width, int height, double fps);
    ~VideoPipe();
    VideoPipe(const VideoPipe&) = delete;
    VideoPipe& operator=(const VideoPipe&) = delete;
    void write(const std::vector<unsigned char>& rgb);
    // Ends the stream and waits for ffmpeg; throws InputError when it failed.
    void close();

  private:
    int finish();  // closes the pipe, waits for ffmpeg, returns its wait status
    std::string path_;
    int fd_ = -1;
    int pid_ = -1;
    size_t frameBytes_;
};

// Frames, fps and ETA on stderr, only when stderr is a terminal.
class ProgressBar {
  public:
    explicit ProgressBar(int total);
    void update(int done, double frame_ms);
    void finish();

  private:
    int total_;
    bool enabled_;
    double started_s_;
};

struct TimingStats {
    double median = 0.0, p95 = 0.0, max = 0.0, mean = 0.0;
};

// Resident memory of this process now (/proc/self/statm) and its peak so far (VmHWM of
// /proc/self/status) [kB]; 0 where /proc is not available.
std::size_t residentMemory_kB();
std::size_t peakResidentMemory_kB();
// Bytes the C heap has handed out and not had back (glibc's mallinfo2) [kB]: what the program
// holds, as against the pages it has touched (RSS, which also counts freed memory the heap keeps
// and the GL driver's mappings); 0 where unknown.
std::size_t heapInUse_kB();

TimingStats timingStats(std::vector<double> values);

class ErrorMeter;
// The measurement's summary as JSON text (error overall and per ring, pop, oracle cost).
std::string measurementJson(const ErrorMeter& meter);
// One row per measured frame: frame, time_s, time_of_day_h, speed_mps, error_mean, error_max,
// error_ring0 .. error_ring<R-1>.
void writeMeasureCsv(const ErrorMeter& meter, const std::string& path);
// One row per reference witness: frame, witness (ring_<r> or the object kind), x, y, z, the
// budget terms (total, truncation, capture, spacing, schedule) and the self-oracle's error.
void writeReferenceCsv(const ErrorMeter& meter, const std::string& path);

struct RunReport {
    std::string replay, backend, glVersion, glRenderer, ambient;
    std::string shadows = "none";  // what shadows the main light (describeShadows)
    int width = 0, height = 0;
    double frameStep_s = 0.0;
    double wall_s = 0.0;
    std::vector<FrameRecord> frames;
    // Ambience volume totals (--ambient volume).
    struct AmbienceTotals {
        std::int64_t facesCaptured = 0, probesCompleted = 0, rejectedProbes = 0, teleports = 0;
        std::size_t captureTriangles = 0;  // triangles per capture face
        std::int64_t inserted = 0, refreshed = 0, expired = 0;
        // Scans of every anchor's coefficients for NaN or infinity (the store must never hold
        // one): how many were made, and the most non-finite anchors one of them found.
        std::int64_t storeScans = 0;
        std::size_t nonFiniteAnchorsMax = 0;
        // The captures' shadow map: renders, their total wall time [ms], triangles of the last.
        std::int64_t captureShadowRenders = 0;
        double captureShadowRender_ms = 0.0;
        std::size_t captureShadowTriangles = 0;
    } ambienceTotals;
    int loops = 1;               // passes over the replay (run --loop)
    std::size_t rssPeak_kB = 0;  // the process's peak resident memory at the end

    // The error measurement (ErrorMeter), as JSON text (empty: not measured).
    std::string measurementJson;

    struct Summary {
        double frameMedian_ms = 0.0, frameP95_ms = 0.0, trianglesMedian = 0.0;
    };
    Summary summary() const;
    // Writes `path` (JSON) and the per-frame rows as CSV beside it (same name, .csv).
    void write(const std::string& path) const;
};

}  // namespace amb
