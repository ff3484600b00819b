// RunReport.cpp — size parsing, ffmpeg pipe, progress of long commands, report.
#include "app/cli/RunReport.h"

#include "lighting/Metrics.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <malloc.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <OpenImageIO/imageio.h>
#include <nlohmann/json.hpp>

#include "world/Error.h"

extern char** environ;

namespace amb {

Size parseSize(const std::string& text, const std::string& where) {
    Size s;
    char x = 0;
    std::istringstream in(text);
    if (!(in >> s.width >> x >> s.height) || (x != 'x' && x != 'X') || !(in >> std::ws).eof()) {
        throw InputError(where, "expected WxH (e.g. 640x360), got '" + text + "'");
    }
    if (s.width < 1 || s.height < 1 || s.width > 16384 || s.height > 16384) {
        throw InputError(where, "size " + text + " out of range (1x1 to 16384x16384)");
    }
    return s;
}

void writeImageRgb8(const std::string& path, int w, int h, const std::vector<unsigned char>& rgb) {
    auto out = OIIO::ImageOutput::create(path);
    if (!out || !out->open(path, OIIO::ImageSpec(w, h, 3, OIIO::TypeDesc::UINT8)) ||
        !out->write_image(OIIO::TypeDesc::UINT8, rgb.data()) || !out->close()) {
        throw InputError(path, "cannot write image");
    }
}

// ---- VideoPipe -------------------------------------------------------------------------------

// ffmpeg is started with an argument vector (posix_spawnp), never through a shell, so no
// character of the output path (which may come from a replay's name) is interpreted. The path
// is passed as "file:<path>" so that ffmpeg reads it as a file name, not an option or protocol.
VideoPipe::VideoPipe(const std::string& path, int width, int height, double fps)
    : path_(path), frameBytes_(size_t(width) * height * 3) {
    std::signal(SIGPIPE, SIG_IGN);
    char rate[32];
    std::snprintf(rate, sizeof(rate), "%.6f", fps);
    // One encoder thread and a fast preset: the renderer shares the CPU with the encoder.
    const std::vector<std::string> args = {
        "ffmpeg", "-nostdin", "-loglevel", "error", "-y", "-f", "rawvideo", "-pix_fmt", "rgb24",
        "-s", std::to_string(width) + "x" + std::to_string(height), "-r", rate, "-i", "pipe:0",
        "-c:v", "libx264", "-preset", "ultrafast", "-crf", "20", "-threads", "1", "-pix_fmt",
        "yuv420p", "file:" + path};
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);

    int fds[2];
    if (pipe2(fds, O_CLOEXEC) != 0) throw InputError(path, "cannot create a pipe for ffmpeg");
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, fds[0], 0);  // dup2 clears O_CLOEXEC on fd 0
    pid_t pid = 0;
    const int rc = posix_spawnp(&pid, "ffmpeg", &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    ::close(fds[0]);
    if (rc != 0) {
        ::close(fds[1]);
        if (rc == ENOENT) {
            throw InputError("--video",
                             "ffmpeg not found on PATH (install the 'ffmpeg' package, or pass "
                             "--no-video)");
        }
        throw InputError(path, std::string("cannot start ffmpeg: ") + std::strerror(rc));
    }
    pid_ = pid;
    fd_ = fds[1];
}

VideoPipe::~VideoPipe() {
    try {
        finish();
    } catch (...) {
    }
}

int VideoPipe::finish() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    if (pid_ <= 0) return 0;
    int status = 0;
    while (waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
    pid_ = -1;
    return status;
}

void VideoPipe::write(const std::vector<unsigned char>& rgb) {
    if (fd_ < 0 || rgb.size() != frameBytes_) return;
    const unsigned char* p = rgb.data();
    std::size_t left = rgb.size();
    while (left > 0) {
        const ssize_t n = ::write(fd_, p, left);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
            finish();
            throw InputError(path_, "ffmpeg stopped accepting frames (see its message above)");
        }
        p += n;
        left -= std::size_t(n);
    }
}

void VideoPipe::close() {
    const int status = finish();
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
        throw InputError(path_, "ffmpeg failed to write the video");
}

// ---- ProgressBar -----------------------------------------------------------------------------

static double nowSeconds() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

double progressInterval_s() {
    const char* text = std::getenv("AMBIENCE_PROGRESS_S");
    if (!text || !*text) return 5.0;
    char* end = nullptr;
    const double v = std::strtod(text, &end);
    if (*end != '\0' || !(v >= 0.05 && v <= 86400.0))
        throw InputError("AMBIENCE_PROGRESS_S",
                         std::string("expected seconds from 0.05 to 86400, got '") + text + "'");
    return v;
}

// "m:ss", or "h:mm:ss" from an hour on; "-:--" when unknown.
static std::string clockText(double s) {
    if (!std::isfinite(s) || s < 0.0) return "-:--";
    const long t = std::lround(s);
    char text[32];
    if (t >= 3600)
        std::snprintf(text, sizeof(text), "%ld:%02ld:%02ld", t / 3600, t / 60 % 60, t % 60);
    else
        std::snprintf(text, sizeof(text), "%ld:%02ld", t / 60, t % 60);
    return text;
}

ProgressBar::ProgressBar(int total, std::string label, std::string unit)
    : ProgressBar(total, std::move(label), std::move(unit), stderr, isatty(STDERR_FILENO) != 0,
                  progressInterval_s()) {}

ProgressBar::ProgressBar(int total, std::string label, std::string unit, std::FILE* to,
                         bool terminal, double interval_s)
    : total_(total),
      label_(std::move(label)),
      unit_(std::move(unit)),
      to_(to),
      terminal_(terminal),
      interval_s_(interval_s),
      started_s_(nowSeconds()) {}

std::string ProgressBar::text(double now_s) const {
    const double elapsed = now_s - started_s_;
    const double rate = done_ > 0 ? done_ / std::max(elapsed, 1e-9) : 0.0;  // per second
    char speed[48] = "";
    if (done_ > 0 && unit_ == "frame")
        std::snprintf(speed, sizeof(speed), ", %.1f fps", rate);
    else if (done_ > 0 && rate >= 1.0)
        std::snprintf(speed, sizeof(speed), ", %.1f %ss/s", rate, unit_.c_str());
    else if (done_ > 0)
        std::snprintf(speed, sizeof(speed), ", %.0f s/%s", 1.0 / rate, unit_.c_str());
    const double left = done_ > 0 ? (total_ - done_) / rate : std::nan("");
    char line[160];
    std::snprintf(line, sizeof(line), "%s %d/%d (%d %%)%s, %s elapsed, %s left", unit_.c_str(),
                  done_, total_, total_ > 0 ? int(100.0 * done_ / total_) : 100, speed,
                  clockText(elapsed).c_str(), clockText(left).c_str());
    return std::string(line) + (detail_.empty() ? "" : ", " + detail_);
}

void ProgressBar::draw(double now_s) {
    lastDrawn_s_ = now_s;
    drawnDone_ = done_;
    drawn_ = true;
    if (terminal_) {
        const int width = 30;
        const int filled =
            total_ > 0 ? std::clamp(int(width * double(done_) / total_), 0, width) : width;
        std::fprintf(to_, "\r\033[K[%s%s] %s", std::string(size_t(filled), '#').c_str(),
                     std::string(size_t(width - filled), '.').c_str(), text(now_s).c_str());
    } else {
        std::fprintf(to_, "%s: %s\n", label_.c_str(), text(now_s).c_str());
    }
    std::fflush(to_);
}

void ProgressBar::update(int done, const std::string& detail) {
    if (finished_) return;
    done_ = done;
    detail_ = detail;
    const double now = nowSeconds();
    // A terminal at most 10 times a second; a log every interval, counted from the start.
    const double since = now - (lastDrawn_s_ < 0.0 ? started_s_ : lastDrawn_s_);
    if (terminal_ ? (since >= 0.1 || done == total_) : since >= interval_s_) draw(now);
}

void ProgressBar::update(int done, double) {
    update(done, std::string());
}

void ProgressBar::note(const std::string& line) {
    if (terminal_ && drawn_) std::fprintf(to_, "\r\033[K");
    std::fprintf(to_, "%s\n", line.c_str());
    if (terminal_ && drawn_) draw(nowSeconds());
    std::fflush(to_);
}

void ProgressBar::finish() {
    if (finished_) return;
    finished_ = true;
    // Off a terminal the end once: not again when the last line already shows it.
    if (terminal_ || drawnDone_ != done_) draw(nowSeconds());
    if (terminal_) std::fprintf(to_, "\n");
    std::fflush(to_);
}

bool isProgressLine(const std::string& line) {
    // "<label>: <unit> <done>/<total> (<percent> %)" and more: what draw() writes off a terminal.
    const std::size_t colon = line.find(": ");
    if (colon == std::string::npos || colon == 0) return false;
    std::istringstream in(line.substr(colon + 2));
    std::string unit;
    int done = 0, total = 0, percent = 0;
    char slash = 0, open = 0;
    std::string rest;
    if (!(in >> unit >> done >> slash >> total >> open >> percent >> rest)) return false;
    return slash == '/' && open == '(' && rest.rfind("%)", 0) == 0;
}

// ---- Memory ----------------------------------------------------------------------------------

std::size_t residentMemory_kB() {
    // statm: total and resident size in pages; one short read, cheap enough for every frame.
    std::FILE* f = std::fopen("/proc/self/statm", "r");
    if (!f) return 0;
    unsigned long total = 0, resident = 0;
    const int n = std::fscanf(f, "%lu %lu", &total, &resident);
    std::fclose(f);
    const long page = sysconf(_SC_PAGESIZE);
    return n == 2 && page > 0 ? std::size_t(resident) * std::size_t(page) / 1024 : 0;
}

std::size_t heapInUse_kB() {
#if defined(__GLIBC__) && (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 33))
    const struct mallinfo2 m = mallinfo2();
    return (m.uordblks + m.hblkhd) / 1024;  // in use in the arenas, plus mmapped blocks
#else
    return 0;
#endif
}

std::size_t peakResidentMemory_kB() {
    std::ifstream in("/proc/self/status");
    std::string line;
    while (std::getline(in, line))
        if (line.rfind("VmHWM:", 0) == 0) return std::strtoull(line.c_str() + 6, nullptr, 10);
    return 0;
}

// ---- Report ----------------------------------------------------------------------------------

TimingStats timingStats(std::vector<double> v) {
    TimingStats s;
    if (v.empty()) return s;
    std::sort(v.begin(), v.end());
    auto quantile = [&](double q) {
        const double pos = q * double(v.size() - 1);
        const size_t i = size_t(pos);
        const double t = pos - double(i);
        return i + 1 < v.size() ? v[i] * (1.0 - t) + v[i + 1] * t : v[i];
    };
    s.median = quantile(0.5);
    s.p95 = quantile(0.95);
    s.max = v.back();
    double sum = 0.0;
    for (double x : v) sum += x;
    s.mean = sum / double(v.size());
    return s;
}

RunReport::Summary RunReport::summary() const {
    std::vector<double> ms, tris;
    for (const FrameRecord& f : frames) {
        ms.push_back(f.frame_ms);
        tris.push_back(double(f.render.triangles));
    }
    return {timingStats(ms).median, timingStats(ms).p95, timingStats(tris).median};
}

namespace {

using nlohmann::json;

json statsJson(const std::vector<double>& v) {
    const TimingStats s = timingStats(v);
    return json{{"median", s.median}, {"p95", s.p95}, {"max", s.max}, {"mean", s.mean}};
}

// What was run and how: the replay, the GL backend, the image and the run's settings.
void addRunSettingsJson(json& j, const RunReport& report) {
    j["replay"] = report.replay;
    j["backend"] = report.backend;
    j["GL_VERSION"] = report.glVersion;
    j["GL_RENDERER"] = report.glRenderer;
    j["size"] = {{"width", report.width}, {"height", report.height}};
    j["ambient"] = report.ambient;
    j["frameStep_s"] = report.frameStep_s;
    j["frameCount"] = report.frames.size();
    j["loops"] = report.loops;
    j["wall_s"] = report.wall_s;
    j["shadows"] = report.shadows;
    j["toneMapping"] = report.toneMapping;
}

// Timing statistics per frame stage and of whole frames, triangle counts and the median fps.
void addTimingsJson(json& j, const std::vector<FrameRecord>& frames) {
    json stages = json::object();
    for (int s = 0; s < kFrameStages; ++s) {
        std::vector<double> v;
        for (const FrameRecord& f : frames) v.push_back(f.stage_ms[s]);
        stages[toString(FrameStage(s))] = statsJson(v);
    }
    std::vector<double> frame_ms, scene_ms, tris, shadow_ms, shadowTris;
    // Drawn patches in the vertex range (nearField.vertexAmbient_m): lit per vertex, and those
    // blending their corners until their turn (nearField.vertexPointsPerFrame).
    std::vector<double> vertexPatches, waitingPatches;
    std::size_t vertexLit = 0, vertexInRange = 0;
    for (const FrameRecord& f : frames) {
        vertexPatches.push_back(double(f.render.terrainPatchesVertex));
        waitingPatches.push_back(double(f.render.terrainPatchesWaiting));
        vertexLit += f.render.terrainPatchesVertex;
        vertexInRange += f.render.terrainPatchesVertex + f.render.terrainPatchesWaiting;
    }
    for (const FrameRecord& f : frames) {
        frame_ms.push_back(f.frame_ms);
        scene_ms.push_back(f.render.scene_ms);
        tris.push_back(double(f.render.triangles));
        shadow_ms.push_back(f.render.shadow_ms);
        shadowTris.push_back(double(f.render.shadowTriangles));
    }
    j["stages_ms"] = stages;
    j["frame_ms"] = statsJson(frame_ms);
    j["drawListBuild_ms"] = statsJson(scene_ms);
    j["triangles"] = statsJson(tris);
    j["terrainVertexPatches"] = statsJson(vertexPatches);
    j["terrainWaitingPatches"] = statsJson(waitingPatches);
    // Of the patch draws in the vertex range over the run, the share lit per vertex (1 with
    // no range).
    j["terrainVertexLitShare"] =
        vertexInRange ? double(vertexLit) / double(vertexInRange) : 1.0;
    // The main view's shadow pass: casters built and submitted (CPU; the rasteriser may finish
    // the maps later, inside the draw), and the triangles drawn into the maps.
    j["shadowPass_ms"] = statsJson(shadow_ms);
    j["shadowTriangles"] = statsJson(shadowTris);
    // --pass-timing: each pass of the main view over the frames that ran it (ms between
    // glFinish calls, triangles, samples passing the depth test) and its mean over all frames.
    bool timed = false;
    for (const FrameRecord& f : frames) timed = timed || f.render.passesTimed;
    if (timed) {
        json passes = json::object();
        for (int p = 0; p < kRenderPasses; ++p) {
            std::vector<double> ms, triangles, samples;
            double total_ms = 0.0;
            std::size_t timedFrames = 0;
            for (const FrameRecord& f : frames) {
                if (!f.render.passesTimed) continue;
                ++timedFrames;
                const PassStats& s = f.render.passes[std::size_t(p)];
                if (!s.ran) continue;
                ms.push_back(s.ms), total_ms += s.ms;
                triangles.push_back(double(s.triangles));
                samples.push_back(double(s.samples));
            }
            passes[toString(RenderPass(p))] = {
                {"frames", ms.size()},
                {"ms", statsJson(ms)},
                {"msPerFrame", timedFrames ? total_ms / double(timedFrames) : 0.0},
                {"triangles_median", timingStats(triangles).median},
                {"samples_median", timingStats(samples).median}};
        }
        j["passes"] = passes;
    }
    const double median = timingStats(frame_ms).median;
    j["fps_median"] = median > 0 ? 1000.0 / median : 0.0;
    j["fps"] = j["fps_median"];
}

void addMemoryJson(json& j, const std::vector<FrameRecord>& frames, std::size_t rssPeak_kB) {
    // Resident memory after each frame, for soak runs: bounded if nothing leaks. The rows
    // of this report (kept until the end) are part of it.
    std::vector<double> rss;
    std::size_t cuts = 0;
    for (const FrameRecord& f : frames) rss.push_back(double(f.rss_kB)), cuts += f.cut;
    j["cameraCuts"] = cuts;
    // What one row of this report holds in memory (rows allocate nothing of their own).
    const std::size_t rowBytes = sizeof(FrameRecord);
    j["memory"] = {{"rssStart_kB", frames.empty() ? 0 : frames.front().rss_kB},
                   {"rssEnd_kB", frames.empty() ? 0 : frames.back().rss_kB},
                   {"rss_kB", statsJson(rss)},
                   {"rssPeak_kB", rssPeak_kB},
                   {"heapStart_kB", frames.empty() ? 0 : frames.front().heap_kB},
                   {"heapEnd_kB", frames.empty() ? 0 : frames.back().heap_kB},
                   {"reportRowBytes", rowBytes}};
}

// The ambience method's summary; only for runs whose frames carry its state (not empty).
json ambienceJson(const RunReport& report) {
    const std::vector<FrameRecord>& frames = report.frames;
    // The ambience's share of frame time: stages 2-5 plus the lookups the draw makes
    // (terrain corners and objects ask the volume while the draw list is built).
    double ambience_ms = 0.0, capture_ms = 0.0, total_ms = 0.0;
    std::vector<double> anchors, bytes, lookup_ms, perFrameAmbience_ms, nearField_ms,
        nearFieldBuild_ms, nearFieldPoints, nearFieldBuilds;
    std::size_t nearFieldBytesMax = 0;
    std::int64_t faces = 0;
    std::size_t maxAnchors = 0, maxBytes = 0;
    for (const FrameRecord& f : frames) {
        ambience_ms += f.stage_ms[int(FrameStage::Predict)] +
                      f.stage_ms[int(FrameStage::Capture)] + f.stage_ms[int(FrameStage::Store)] +
                      f.stage_ms[int(FrameStage::Interpolate)] + f.ambience.lookup_ms;
        perFrameAmbience_ms.push_back(
            f.stage_ms[int(FrameStage::Predict)] + f.stage_ms[int(FrameStage::Capture)] +
            f.stage_ms[int(FrameStage::Store)] + f.stage_ms[int(FrameStage::Interpolate)] +
            f.ambience.lookup_ms);
        faces += f.ambience.faces;
        capture_ms += f.stage_ms[int(FrameStage::Capture)];
        total_ms += f.frame_ms;
        anchors.push_back(double(f.ambience.anchors));
        bytes.push_back(double(f.ambience.bytes));
        lookup_ms.push_back(f.ambience.lookup_ms);
        nearField_ms.push_back(f.ambience.nearField_ms);
        nearFieldBuild_ms.push_back(f.ambience.nearFieldBuild_ms);
        nearFieldPoints.push_back(double(f.ambience.nearFieldPoints));
        nearFieldBuilds.push_back(double(f.ambience.nearFieldBuilds));
        nearFieldBytesMax = std::max(nearFieldBytesMax, f.ambience.nearFieldBytes);
        maxAnchors = std::max(maxAnchors, f.ambience.anchors);
        maxBytes = std::max(maxBytes, f.ambience.bytes);
    }
    const FrameRecord& last = frames.back();
    const auto& t = report.ambienceTotals;
    const double frameStep_s = report.frameStep_s;
    json a = {
        {"anchorsEnd", last.ambience.anchors},
        {"anchorsMax", maxAnchors},
        {"anchors", statsJson(anchors)},
        {"bytesEnd", last.ambience.bytes},
        {"bytesMax", maxBytes},
        {"bytesPerAnchorEnd", last.ambience.anchors
                                  ? double(last.ambience.bytes) / double(last.ambience.anchors)
                                  : 0.0},
        {"facesCaptured", t.facesCaptured},
        {"primeFaces", t.primeFaces},
        {"probesCompleted", t.probesCompleted},
        {"rejectedProbes", t.rejectedProbes},
        {"teleports", t.teleports},
        {"anchorsInserted", t.inserted},
        {"anchorsRefreshed", t.refreshed},
        {"anchorsExpired", t.expired},
        {"captureTrianglesPerFace", t.captureTriangles},
        // The captures' shadow map (app/render/ShadowMap.h), part of the capture stage.
        {"captureShadowRenders", t.captureShadowRenders},
        {"captureShadowRender_ms", t.captureShadowRender_ms},
        {"captureShadowRenderMean_ms",
         t.captureShadowRenders ? t.captureShadowRender_ms / double(t.captureShadowRenders) : 0.0},
        {"captureShadowTriangles", t.captureShadowTriangles},
        {"storeScans", t.storeScans},
        {"nonFiniteAnchorsMax", t.nonFiniteAnchorsMax},
        {"lookup_ms", statsJson(lookup_ms)},
        // The near field's share of the lookups (0 without it), and its cache's memory.
        {"nearField_ms", statsJson(nearField_ms)},
        // Of which building the transfers of points not in the cache, and the points per frame.
        {"nearFieldBuild_ms", statsJson(nearFieldBuild_ms)},
        {"nearFieldPoints", statsJson(nearFieldPoints)},
        {"nearFieldBuilds", statsJson(nearFieldBuilds)},
        {"nearFieldBytesMax", nearFieldBytesMax},
        // Stages 2-5 and the draw's lookups, per frame.
        {"ambience_ms", statsJson(perFrameAmbience_ms)},
        {"facesPerSecond", frames.size() > 1 && frameStep_s > 0
                               ? double(faces) / (double(frames.size()) * frameStep_s)
                               : 0.0},
        {"shareOfFrameTime", total_ms > 0 ? ambience_ms / total_ms : 0.0},
        {"captureShareOfFrameTime", total_ms > 0 ? capture_ms / total_ms : 0.0},
    };
    // Only a method with an anchor store is scanned.
    if (t.storeScans > 0) a["storeFinite"] = t.nonFiniteAnchorsMax == 0;
    return a;
}

// One frame's row of the JSON report; `volume`: the frames carry the ambience method's state.
json frameRowJson(const FrameRecord& f, bool volume) {
    json r{{"frame", f.index},
           {"loop", f.loop},
           {"time_s", f.time_s},
           {"replayTime_s", f.replayTime_s},
           {"cut", f.cut},
           {"rss_kB", f.rss_kB},
           {"heap_kB", f.heap_kB},
           {"timeOfDay_h", f.timeOfDay_h},
           {"frame_ms", f.frame_ms},
           {"triangles", f.render.triangles},
           {"terrainPatches", f.render.terrainPatches},
           {"terrainPatchesDrawn", f.render.terrainPatchesDrawn},
           {"objectsDrawn", f.render.objectsDrawn},
           {"terrainRebuilt", f.render.terrainRebuilt},
           {"terrainPatchesVertex", f.render.terrainPatchesVertex},
           {"terrainPatchesWaiting", f.render.terrainPatchesWaiting}};
    for (int s = 0; s < kFrameStages; ++s)
        r[std::string(toString(FrameStage(s))) + "_ms"] = f.stage_ms[s];
    if (volume) {
        r["anchors"] = f.ambience.anchors;
        r["anchorBytes"] = f.ambience.bytes;
        r["facesCaptured"] = f.ambience.faces;
        r["finestLevel"] = f.ambience.finestLevel;
        r["ambientLookups"] = f.ambience.lookups;
        r["ambientLookup_ms"] = f.ambience.lookup_ms;
        r["volumePredict_ms"] = f.ambience.predict_ms;
        r["volumeCapture_ms"] = f.ambience.capture_ms;
        r["volumeProject_ms"] = f.ambience.project_ms;
        r["volumeStore_ms"] = f.ambience.store_ms;
        r["anchorsPerLevel"] =
            std::vector<std::size_t>(f.ambience.anchorsPerLevel.begin(),
                                     f.ambience.anchorsPerLevel.begin() + f.ambience.levels);
    }
    return r;
}

// The summary `head` followed by the "frames" array of per-frame rows.
void writeReportJson(const std::string& path, const json& head,
                     const std::vector<FrameRecord>& frames, bool volume) {
    std::ofstream out(path);
    if (!out) throw InputError(path, "cannot write the report");
    // The rows are written one at a time, each on one line: a JSON tree of an hour's rows would
    // take hundreds of MB.
    std::string text = head.dump(1);  // "{\n ... \n}": drop the "\n}" and go on with the rows
    text.resize(text.size() - 2);
    out << text << ",\n \"frames\": [";
    bool firstRow = true;
    for (const FrameRecord& f : frames) {
        out << (firstRow ? "\n  " : ",\n  ") << frameRowJson(f, volume).dump();
        firstRow = false;
    }
    out << "\n ]\n}\n";
    if (!out) throw InputError(path, "cannot write the report");
}

// The per-frame rows as CSV; the volume's columns (one per anchor level of the first frame) only
// when the frames carry the ambience method's state.
void writeReportCsv(const std::string& csvPath, const std::vector<FrameRecord>& frames,
                    bool volume) {
    std::ofstream csv(csvPath);
    if (!csv) throw InputError(csvPath, "cannot write the report CSV");
    csv << "frame,time_s,timeOfDay_h,frame_ms";
    for (int s = 0; s < kFrameStages; ++s) csv << "," << toString(FrameStage(s)) << "_ms";
    csv << ",triangles,terrainPatches,terrainPatchesDrawn,objectsDrawn,terrainRebuilt";
    const std::size_t csvLevels = volume ? std::size_t(frames.front().ambience.levels) : 0;
    if (volume) {
        csv << ",anchors,anchorBytes,facesCaptured,finestLevel,ambientLookups,ambientLookup_ms"
               ",volumePredict_ms,volumeCapture_ms,volumeProject_ms,volumeStore_ms";
        for (std::size_t l = 0; l < csvLevels; ++l) csv << ",anchorsLevel" << l;
    }
    csv << ",rss_kB,heap_kB,cut,loop,popMove\n";
    for (const FrameRecord& f : frames) {
        csv << f.index << "," << f.time_s << "," << f.timeOfDay_h << "," << f.frame_ms;
        for (int s = 0; s < kFrameStages; ++s) csv << "," << f.stage_ms[s];
        csv << "," << f.render.triangles << "," << f.render.terrainPatches << ","
            << f.render.terrainPatchesDrawn << "," << f.render.objectsDrawn << ","
            << (f.render.terrainRebuilt ? 1 : 0);
        if (volume) {
            csv << "," << f.ambience.anchors << "," << f.ambience.bytes << "," << f.ambience.faces
                << "," << f.ambience.finestLevel << "," << f.ambience.lookups << ","
                << f.ambience.lookup_ms << "," << f.ambience.predict_ms << "," << f.ambience.capture_ms
                << "," << f.ambience.project_ms << "," << f.ambience.store_ms;
            for (std::size_t l = 0; l < csvLevels; ++l) {
                const bool held = l < std::size_t(f.ambience.levels);
                csv << "," << (held ? f.ambience.anchorsPerLevel[l] : 0);
            }
        }
        csv << "," << f.rss_kB << "," << f.heap_kB << "," << (f.cut ? 1 : 0) << "," << f.loop
            << ",";
        if (std::isfinite(f.popMove)) csv << f.popMove;  // empty: no pop measured this frame
        csv << "\n";
    }
    if (!csv) throw InputError(csvPath, "cannot write the report CSV");
}

}  // namespace

void RunReport::write(const std::string& path) const {
    const bool volume = !frames.empty() && frames.front().ambience.active;
    json j;
    addRunSettingsJson(j, *this);
    addTimingsJson(j, frames);
    addMemoryJson(j, frames, rssPeak_kB);
    if (volume) j["ambience"] = ambienceJson(*this);
    if (!measurementJson.empty()) j["measurement"] = json::parse(measurementJson);
    writeReportJson(path, j, frames, volume);
    const std::string csvPath = std::filesystem::path(path).replace_extension(".csv").string();
    writeReportCsv(csvPath, frames, volume);
}

// ---- Measurement ---------------------------------------------------------------------------

std::string measurementJson(const ErrorMeter& meter) {
    using nlohmann::json;
    auto summaryJson = [](const Summary& s) {
        return json{{"count", s.count}, {"mean", s.mean}, {"p50", s.p50},
                    {"p95", s.p95},     {"p99", s.p99},   {"max", s.max}};
    };
    const MeasureSettings& ms = meter.settings();
    json rings = json::array();
    for (int r = 0; r < ms.rings(); ++r)
        rings.push_back(summaryJson(summarize(meter.ringErrors(r))));
    double speed = 0.0;
    for (const auto& m : meter.measured()) speed += m.speed_mps;
    const std::size_t n = meter.measured().size();
    json j{{"every", ms.every},
           {"measuredFrames", n},
           {"ringRadii_m", ms.ringRadii},
           {"witnessesPerRing", ms.perRing},
           {"error", summaryJson(summarize(meter.errors()))},
           {"errorByRing", rings},
           {"pop", summaryJson(summarize(meter.pops()))},
           {"pop_move", summaryJson(summarize(meter.movingPops()))},
           {"meanSpeed_mps", n ? speed / double(n) : 0.0},
           {"oracle_s", meter.oracleSeconds()},
           {"oracleCaptures", meter.oracleCaptures()},
           {"oracleCacheHits", meter.oracleCacheHits()},
           {"oracle", toString(meter.oracleKind())},
           {"metric",
            "relative L2 distance of irradiance over the sphere of normals, luminance-weighted "
            "channels (lighting/Metrics.h)"}};
    if (meter.hasReference()) {
        const auto budgetJson = [&summaryJson](const std::vector<BudgetTerms>& terms) {
            const BudgetSummary b = summarizeBudget(terms);
            const auto num = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
            std::vector<double> totals, selfs;
            for (const BudgetTerms& t : terms) totals.push_back(t.total), selfs.push_back(t.self);
            return json{{"count", b.count},           {"rmsTotal", num(b.total)},
                        {"truncation", num(b.truncation)}, {"capture", num(b.capture)},
                        {"spacing", num(b.spacing)},    {"schedule", num(b.schedule)},
                        {"closure", num(b.closure())},  {"error", summaryJson(summarize(totals))},
                        {"selfError", summaryJson(summarize(selfs))}};
        };
        const ReferenceSettings& rs = meter.referenceSettings();
        json screenJson = {{"error", summaryJson(summarize(meter.screenErrors()))},
                           {"leftOut", meter.screenLeftOut()}};
        for (int k = 1; k <= kSurfaceKinds; ++k)
            screenJson[toString(SurfaceKind(k))] = summaryJson(summarize(meter.screenErrors(k)));
        json rings = json::array();
        for (int r = 0; r < ms.rings(); ++r) rings.push_back(budgetJson(meter.terrainBudget(r)));
        // The terrain witnesses as the screen shows them (ReferenceWitness::drawnError).
        json drawnJson = {{"error", summaryJson(summarize(meter.drawnErrors()))},
                          {"open", summaryJson(summarize(meter.drawnErrors(-1, 0)))},
                          {"underCrown", summaryJson(summarize(meter.drawnErrors(-1, 1)))},
                          {"hidden", meter.hiddenWitnesses()},
                          {"terrainWitnesses", meter.terrainBudget().size()},
                          {"movedAside", meter.placedWitnesses(ProbePlacement::MovedAside)},
                          {"lifted", meter.placedWitnesses(ProbePlacement::Lifted)}};
        json drawnRings = json::array();
        for (int r = 0; r < ms.rings(); ++r)
            drawnRings.push_back(summaryJson(summarize(meter.drawnErrors(r))));
        drawnJson["byRing"] = drawnRings;
        // Its budget that closes (DrawnBudget, lighting/Metrics.h): the mean drawn error as
        // far field + patch + model + truncation, over the witnesses with all four steps.
        const auto drawnBudgetJson = [](const std::vector<DrawnBudget>& budgets) {
            const DrawnBudgetSummary b = summarizeDrawnBudget(budgets);
            return json{{"count", b.count},      {"drawn", b.drawn},
                        {"farField", b.farField}, {"patch", b.patch},
                        {"model", b.model},       {"truncation", b.truncation},
                        {"closure", b.closure()},
                        {"perPoint", std::isfinite(b.perPoint) ? json(b.perPoint) : json(nullptr)},
                        {"drawnBias", std::isfinite(b.drawnBias) ? json(b.drawnBias) : json(nullptr)},
                        {"atPointBias",
                         std::isfinite(b.atPointBias) ? json(b.atPointBias) : json(nullptr)},
                        {"sceneBias", std::isfinite(b.sceneBias) ? json(b.sceneBias) : json(nullptr)},
                        {"placedBias",
                         std::isfinite(b.placedBias) ? json(b.placedBias) : json(nullptr)}};
        };
        drawnJson["budget"] = drawnBudgetJson(meter.drawnBudgets());
        drawnJson["budgetOpen"] = drawnBudgetJson(meter.drawnBudgets(-1, 0));
        drawnJson["budgetUnderCrown"] = drawnBudgetJson(meter.drawnBudgets(-1, 1));
        json drawnBudgetRings = json::array();
        for (int r = 0; r < ms.rings(); ++r)
            drawnBudgetRings.push_back(drawnBudgetJson(meter.drawnBudgets(r)));
        drawnJson["budgetByRing"] = drawnBudgetRings;
        json objects = json::object();
        for (int k = 0; k < kObjectKinds; ++k) {
            json o = budgetJson(meter.objectBudget(ObjectKind(k)));
            // At the drawn normal (ReferenceWitness::drawnError), with its signed bias.
            o["drawn"] = summaryJson(summarize(meter.objectDrawnErrors(ObjectKind(k))));
            o["drawnBias"] = summaryJson(summarize(meter.objectDrawnErrors(ObjectKind(k), true)));
            objects[toString(ObjectKind(k))] = o;
        }
        j["reference"] = {{"faceSize", rs.faceSize},
                          {"scene", "full"},
                          {"every", rs.every},
                          {"ruleDirections", json(sphereProductRule(rs.legendreNodes).directions.size())},
                          {"budget", budgetJson(meter.terrainBudget())},
                          {"budgetByRing", rings},
                          {"objects", objects},
                          {"screen", screenJson},
                          {"drawn", drawnJson},
                          {"reference_s", meter.referenceSeconds()},
                          {"referenceCaptures", meter.referenceCaptures()},
                          {"referenceCacheHits", meter.referenceCacheHits()}};
    }
    return j.dump();
}

void writeMeasureCsv(const ErrorMeter& meter, const std::string& path) {
    std::ofstream out(path);
    if (!out) throw InputError(path, "cannot write the measurement CSV");
    const int rings = meter.settings().rings();
    out << "frame,time_s,time_of_day_h,speed_mps,error_mean,error_max";
    for (int r = 0; r < rings; ++r) out << ",error_ring" << r;
    out << "\n";
    out.precision(9);
    for (const auto& m : meter.measured()) {
        out << m.index << ',' << m.time_s << ',' << m.timeOfDay_h << ',' << m.speed_mps << ','
            << m.mean() << ',' << m.max();
        for (int r = 0; r < rings; ++r) {
            const double v = m.ringMean(r);
            out << ',';
            if (std::isfinite(v)) out << v;
        }
        out << "\n";
    }
    if (!out) throw InputError(path, "cannot write the measurement CSV");
}

void writeScreenCsv(const ErrorMeter& meter, const std::string& path) {
    std::ofstream out(path);
    if (!out) throw InputError(path, "cannot write the screen CSV");
    out << "frame,kind,error,bias,x,y,z,nx,ny,nz\n";
    out.precision(9);
    for (const ScreenResult& r : meter.screenResults())
        out << r.frame << ',' << toString(r.kind) << ',' << r.error << ',' << r.bias << ','
            << r.position_m.x << ',' << r.position_m.y << ',' << r.position_m.z << ','
            << r.normal.x << ',' << r.normal.y << ',' << r.normal.z << "\n";
    if (!out) throw InputError(path, "cannot write the screen CSV");
}

void writeReferenceCsv(const ErrorMeter& meter, const std::string& path) {
    std::ofstream out(path);
    if (!out) throw InputError(path, "cannot write the reference CSV");
    out << "frame,witness,x,y,z,total,truncation,capture,spacing,schedule,self,drawn,cover,"
           "placed,drawn_fresh_far,drawn_at_point,drawn_truncation,drawn_per_point,drawn_bias,"
           "drawn_at_point_bias,drawn_scene_bias,drawn_placed_bias\n";
    out.precision(9);
    for (const ReferenceWitness& r : meter.referenceWitnesses()) {
        out << r.frame << ','
            << (r.ring >= 0 ? "ring_" + std::to_string(r.ring) : std::string(toString(r.object)))
            << ',' << r.position_m.x << ',' << r.position_m.y << ',' << r.position_m.z << ','
            << r.terms.total << ',' << r.terms.truncation << ',' << r.terms.capture << ',';
        if (std::isfinite(r.terms.spacing)) out << r.terms.spacing;
        out << ',' << r.terms.schedule << ',' << r.terms.self << ',';
        if (std::isfinite(r.drawnError)) out << r.drawnError;
        out << ','
            << (r.ring < 0                                ? ""
                : r.cover == GroundCover::UnderCrown ? "crown"
                : r.cover == GroundCover::Hidden     ? "hidden"
                                                     : "open")
            << ',' << (r.ring < 0 ? "" : toString(r.placement));
        const DrawnBudget& b = r.drawnBudget;
        for (const double v :
             {b.freshFar, b.atPoint, b.truncation, b.perPoint, b.drawnBias, b.atPointBias,
              b.sceneBias, b.placedBias}) {
            out << ',';
            if (std::isfinite(v)) out << v;
        }
        out << "\n";
    }
    if (!out) throw InputError(path, "cannot write the reference CSV");
}

}  // namespace amb
