// RunReport.h — what `ambience run` (and `view`) share: image size parsing, the ffmpeg video
// pipe, the progress of long commands, and the report (JSON with timing statistics, per-frame
// rows, CSV).
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

// Progress of a long command (`run` frames, `bench` runs) on stderr, one implementation for
// both. On a terminal: a bar redrawn in place. Elsewhere (CI logs, cluster jobs): a plain line
// every few seconds, e.g. "run: frame 1200/2701 (44 %), 31.0 fps, 0:38 elapsed, 0:49 left",
// and one at the end (unless the last already shows it). The interval is AMBIENCE_PROGRESS_S
// seconds (default 5; 0.05 to 86400).
class ProgressBar {
  public:
    // `label` opens every line ("run", "bench"), `unit` names what is counted ("frame", "run").
    explicit ProgressBar(int total, std::string label = "run", std::string unit = "frame");
    // For tests: where to write, whether that is a terminal, and the line interval [s].
    ProgressBar(int total, std::string label, std::string unit, std::FILE* to, bool terminal,
                double interval_s);
    // `done` of the total so far; draws when due (a terminal at most 10 times a second).
    void update(int done, const std::string& detail = "");
    void update(int done, double frame_ms);  // `run`'s per-frame call
    // A line of its own (above the bar on a terminal), e.g. a run that failed.
    void note(const std::string& line);
    // The last state: the bar's line ended, or a final plain line.
    void finish();
    bool terminal() const { return terminal_; }

  private:
    void draw(double now_s);
    std::string text(double now_s) const;  // the plain line without the label
    int total_, done_ = 0;
    std::string label_, unit_, detail_;
    std::FILE* to_;
    bool terminal_, drawn_ = false, finished_ = false;
    double interval_s_, started_s_, lastDrawn_s_ = -1.0;
    int drawnDone_ = -1;  // `done` in the last line drawn
};

// True for a line ProgressBar writes when not on a terminal (so a log's last lines can be read
// without them).
bool isProgressLine(const std::string& line);

// The line interval from AMBIENCE_PROGRESS_S (default 5 s); InputError for a value that is not
// a number of seconds from 0.05 to 86400.
double progressInterval_s();

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
// screen.csv: one row per screen witness, "frame,kind,error,bias,x,y,z,nx,ny,nz" (kind terrain,
// road or object; bias the signed luminance ratio less one; the surface point and its normal),
// in the order they were taken (a frame's first k rows are what --screen-witnesses k takes).
void writeScreenCsv(const ErrorMeter& meter, const std::string& path);

struct RunReport {
    std::string replay, backend, glVersion, glRenderer, ambient;
    // How the frames were tone mapped (the exposure and the curve), as the report states it.
    std::string toneMapping =
        "exposure (white Lambertian at 0.6), ACES filmic fit (Narkowicz 2015), sRGB";
    std::string shadows = "none";  // what shadows the main light (describeShadows)
    int width = 0, height = 0;
    double frameStep_s = 0.0;
    double wall_s = 0.0;
    std::vector<FrameRecord> frames;
    // Ambience volume totals (--ambient volume).
    struct AmbienceTotals {
        std::int64_t facesCaptured = 0, probesCompleted = 0, rejectedProbes = 0, teleports = 0;
        std::int64_t primeFaces = 0;  // of facesCaptured, the primes' (lighting/CaptureCore.h)
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
