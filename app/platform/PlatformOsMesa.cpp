// PlatformOsMesa.cpp — software GL 4.5 core through OSMesa (Mesa's off-screen interface).
// The context renders into the renderer's framebuffer objects; the client buffer OSMesa needs
// to make the context current is allocated at the requested size but not read.
#include <vector>

#include <glad/gl.h>
// OSMesa after glad: glad's header must be the first GL header (osmesa.h includes GL/gl.h).
#include <GL/osmesa.h>

#include "app/platform/Platform.h"

namespace amb {
namespace {

class PlatformOsMesa final : public Platform {
  public:
    PlatformOsMesa(int width, int height)
        : width_(width), height_(height), buffer_(size_t(width) * size_t(height) * 4) {
        const int attribs[] = {OSMESA_FORMAT,
                               OSMESA_RGBA,
                               OSMESA_DEPTH_BITS,
                               0,
                               OSMESA_PROFILE,
                               OSMESA_CORE_PROFILE,
                               OSMESA_CONTEXT_MAJOR_VERSION,
                               4,
                               OSMESA_CONTEXT_MINOR_VERSION,
                               5,
                               0};
        context_ = OSMesaCreateContextAttribs(attribs, nullptr);
        if (!context_) throw PlatformUnavailable("osmesa: no GL 4.5 core context");
        if (!OSMesaMakeCurrent(context_, buffer_.data(), GL_UNSIGNED_BYTE, width, height)) {
            OSMesaDestroyContext(context_);
            throw PlatformUnavailable("osmesa: OSMesaMakeCurrent failed");
        }
        try {
            loadGl(reinterpret_cast<GlProc (*)(const char*)>(&OSMesaGetProcAddress), "osmesa");
        } catch (...) {
            OSMesaDestroyContext(context_);
            throw;
        }
    }
    ~PlatformOsMesa() override {
        OSMesaMakeCurrent(nullptr, nullptr, 0, 0, 0);
        OSMesaDestroyContext(context_);
    }

    Backend backend() const override { return Backend::OsMesa; }
    int width() const override { return width_; }
    int height() const override { return height_; }

  private:
    int width_, height_;
    std::vector<unsigned char> buffer_;
    OSMesaContext context_ = nullptr;
};

}  // namespace

std::unique_ptr<Platform> createOsMesaPlatform(int width, int height) {
    return std::make_unique<PlatformOsMesa>(width, height);
}

}  // namespace amb
