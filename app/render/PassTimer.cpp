// PassTimer.cpp — glFinish-bracketed pass times and sample counts.
#include "app/render/PassTimer.h"

namespace amb {

PassTimer::~PassTimer() {
    if (query_) glDeleteQueries(1, &query_);
}

void PassTimer::begin(RenderPass p) {
    if (!enabled_) return;
    if (open_ >= 0) end(0);
    if (!query_) glCreateQueries(GL_SAMPLES_PASSED, 1, &query_);
    glFinish();
    open_ = int(p);
    start_ = std::chrono::steady_clock::now();
    glBeginQuery(GL_SAMPLES_PASSED, query_);
}

void PassTimer::end(std::size_t triangles) {
    if (!enabled_ || open_ < 0) return;
    glEndQuery(GL_SAMPLES_PASSED);
    glFinish();
    const auto stop = std::chrono::steady_clock::now();
    GLuint64 samples = 0;
    glGetQueryObjectui64v(query_, GL_QUERY_RESULT, &samples);
    PassStats& s = passes_[std::size_t(open_)];
    s.ran = true;
    s.ms += std::chrono::duration<double, std::milli>(stop - start_).count();
    s.triangles += triangles;
    s.samples += samples;
    open_ = -1;
}

}  // namespace amb
