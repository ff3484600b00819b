// PlatformEgl.cpp — headless GL 4.5 core through EGL without any surface.
//
// Steps: (1) with EGL_EXT_platform_device, look for a hardware device (one that has a DRM node)
// and use it, so a machine with a GPU renders on it; (2) otherwise the Mesa surfaceless platform
// (EGL_PLATFORM_SURFACELESS_MESA), which is llvmpipe on a machine without a GPU; (3) a context
// without a config (EGL_KHR_no_config_context) made current without a surface
// (EGL_KHR_surfaceless_context). Rendering goes to the renderer's framebuffer objects.
#include <cstring>
#include <vector>

#include <glad/gl.h>
// EGL after glad: glad's header must be the first GL header.
#include <EGL/egl.h>
#include <EGL/eglext.h>

#include "app/platform/Platform.h"

namespace amb {
namespace {

bool hasExtension(const char* list, const char* name) {
    if (!list) return false;
    const size_t n = std::strlen(name);
    for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n) {
        if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
    }
    return false;
}

class PlatformEgl final : public Platform {
  public:
    PlatformEgl(int width, int height) : width_(width), height_(height) {
        display_ = openDisplay();
        if (display_ == EGL_NO_DISPLAY) {
            throw PlatformUnavailable("egl: no EGL display (surfaceless or device platform)");
        }
        EGLint major = 0, minor = 0;
        if (!eglInitialize(display_, &major, &minor)) {
            throw PlatformUnavailable("egl: eglInitialize failed");
        }
        const char* ext = eglQueryString(display_, EGL_EXTENSIONS);
        if (!hasExtension(ext, "EGL_KHR_surfaceless_context") ||
            !hasExtension(ext, "EGL_KHR_no_config_context")) {
            eglTerminate(display_);
            throw PlatformUnavailable("egl: display lacks surfaceless / no-config contexts");
        }
        if (!eglBindAPI(EGL_OPENGL_API)) {
            eglTerminate(display_);
            throw PlatformUnavailable("egl: desktop OpenGL API not available");
        }
        const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION,
                                  4,
                                  EGL_CONTEXT_MINOR_VERSION,
                                  5,
                                  EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                  EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                  EGL_NONE};
        context_ = eglCreateContext(display_, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attribs);
        if (context_ == EGL_NO_CONTEXT) {
            eglTerminate(display_);
            throw PlatformUnavailable("egl: no GL 4.5 core context");
        }
        if (!eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_)) {
            eglDestroyContext(display_, context_);
            eglTerminate(display_);
            throw PlatformUnavailable("egl: eglMakeCurrent failed");
        }
        try {
            loadGl(reinterpret_cast<GlProc (*)(const char*)>(&eglGetProcAddress), "egl");
        } catch (...) {
            release();
            throw;
        }
    }
    ~PlatformEgl() override { release(); }

    Backend backend() const override { return Backend::Egl; }
    int width() const override { return width_; }
    int height() const override { return height_; }

  private:
    static EGLDisplay openDisplay() {
        const char* clientExt = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
        if (hasExtension(clientExt, "EGL_EXT_platform_device")) {
            auto queryDevices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(
                eglGetProcAddress("eglQueryDevicesEXT"));
            auto queryDeviceString = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(
                eglGetProcAddress("eglQueryDeviceStringEXT"));
            EGLint count = 0;
            if (queryDevices && queryDeviceString && queryDevices(0, nullptr, &count) &&
                count > 0) {
                std::vector<EGLDeviceEXT> devices(count);
                queryDevices(count, devices.data(), &count);
                for (EGLDeviceEXT device : devices) {
                    // A hardware device names a DRM node; the software one does not.
                    const char* devExt = queryDeviceString(device, EGL_EXTENSIONS);
                    if (!hasExtension(devExt, "EGL_EXT_device_drm")) continue;
                    EGLDisplay d = eglGetPlatformDisplay(EGL_PLATFORM_DEVICE_EXT, device, nullptr);
                    if (d != EGL_NO_DISPLAY) return d;
                }
            }
        }
        if (hasExtension(clientExt, "EGL_MESA_platform_surfaceless")) {
            return eglGetPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA,
                                         reinterpret_cast<void*>(EGL_DEFAULT_DISPLAY), nullptr);
        }
        return EGL_NO_DISPLAY;
    }

    void release() {
        if (display_ == EGL_NO_DISPLAY) return;
        eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        if (context_ != EGL_NO_CONTEXT) eglDestroyContext(display_, context_);
        eglTerminate(display_);
        eglReleaseThread();
        display_ = EGL_NO_DISPLAY;
        context_ = EGL_NO_CONTEXT;
    }

    int width_, height_;
    EGLDisplay display_ = EGL_NO_DISPLAY;
    EGLContext context_ = EGL_NO_CONTEXT;
};

}  // namespace

std::unique_ptr<Platform> createEglPlatform(int width, int height) {
    return std::make_unique<PlatformEgl>(width, height);
}

}  // namespace amb
