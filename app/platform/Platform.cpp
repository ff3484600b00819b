// Platform.cpp — backend names, the offscreen fallback chain (EGL, then OSMesa), GL loading.
#include "app/platform/Platform.h"

#include <glad/gl.h>

#include "world/Error.h"

namespace amb {

Backend parseBackend(const std::string& text, const std::string& where) {
    if (text == "auto") return Backend::Auto;
    if (text == "egl") return Backend::Egl;
    if (text == "osmesa") return Backend::OsMesa;
    if (text == "glfw") return Backend::Glfw;
    throw InputError(where, "unknown backend '" + text + "' (expected auto, egl or osmesa)");
}

const char* toString(Backend backend) {
    switch (backend) {
        case Backend::Auto:
            return "auto";
        case Backend::Egl:
            return "egl";
        case Backend::OsMesa:
            return "osmesa";
        case Backend::Glfw:
            return "glfw";
    }
    return "?";
}

static std::string glString(GLenum name) {
    const GLubyte* s = glGetString(name);
    return s ? reinterpret_cast<const char*>(s) : "";
}

std::string Platform::glVersion() const {
    return glString(GL_VERSION);
}
std::string Platform::glRenderer() const {
    return glString(GL_RENDERER);
}

void loadGl(GlProc (*getProcAddress)(const char* name), const char* platform) {
    const int version = gladLoadGL(reinterpret_cast<GLADloadfunc>(getProcAddress));
    if (version == 0) {
        throw PlatformUnavailable(std::string(platform) + ": could not load GL entry points");
    }
    const int major = GLAD_VERSION_MAJOR(version), minor = GLAD_VERSION_MINOR(version);
    if (major * 10 + minor < 45) {
        throw PlatformUnavailable(std::string(platform) + ": GL " + std::to_string(major) + "." +
                                  std::to_string(minor) + " context, 4.5 core needed");
    }
}

std::unique_ptr<Platform> createOffscreenPlatform(Backend backend, int width, int height) {
    if (width <= 0 || height <= 0) {
        throw InputError("size", "width and height must be positive");
    }
    switch (backend) {
        case Backend::Egl:
            return createEglPlatform(width, height);
        case Backend::OsMesa:
            return createOsMesaPlatform(width, height);
        case Backend::Glfw:
            return createGlfwPlatform(width, height, "ambience", false);
        case Backend::Auto:
            break;
    }
    std::string reasons;
    try {
        return createEglPlatform(width, height);
    } catch (const PlatformUnavailable& e) {
        reasons = e.what();
    }
    try {
        return createOsMesaPlatform(width, height);
    } catch (const PlatformUnavailable& e) {
        reasons += std::string("; ") + e.what();
    }
    throw PlatformUnavailable("no offscreen GL 4.5 core platform: " + reasons);
}

}  // namespace amb
