// Platform.h — "give me a GL 4.5 core context and a surface": a window, or W x H offscreen.
//
// Three small implementations of one interface (docs/ARCHITECTURE.md "Style": headless is a platform,
// not a special case): EGL surfaceless or device (PlatformEgl.cpp), OSMesa software
// (PlatformOsMesa.cpp) and a GLFW window (PlatformGlfw.cpp). Offscreen platforms render into
// framebuffer objects owned by the renderer; the platform only provides the current context. GL
// entry points are loaded with glad from the platform's own GetProcAddress once the context is
// current.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>

namespace amb {

enum class Backend { Auto, Egl, OsMesa, Glfw };

// "auto", "egl", "osmesa" or "glfw"; throws InputError (naming `where`) for anything else.
Backend parseBackend(const std::string& text, const std::string& where);
const char* toString(Backend backend);

// The keys and mouse buttons the viewer reads (`ambience view`), so that nothing above the
// platform names GLFW's.
enum class Key {
    W, A, S, D, Q, E, LeftShift,                         // free flight
    Escape, Tab, F, Space, Left, Right, LeftBracket, RightBracket, R, P,  // commands
};
inline constexpr int kKeyCount = int(Key::P) + 1;
enum class MouseButton { Left, Right };
// The cursor in screen coordinates from the window's top left corner.
struct CursorPosition {
    double x = 0.0, y = 0.0;
};

class Platform {
  public:
    virtual ~Platform() = default;
    virtual Backend backend() const = 0;
    // Offscreen platforms have no window; their default framebuffer is not used.
    virtual bool hasWindow() const { return false; }
    // Framebuffer size in pixels (for a window, it may change when the user resizes).
    virtual int width() const = 0;
    virtual int height() const = 0;
    // Window only: present, poll input; offscreen: no-ops.
    virtual void swapBuffers() {}
    virtual void pollEvents() {}
    virtual bool shouldClose() const { return false; }
    // The native window (GLFWwindow*) for the panel's input backend (app/render/PanelRenderer.h),
    // or nullptr.
    virtual void* nativeWindow() const { return nullptr; }
    // Window only: the keyboard and the mouse as of the last pollEvents; offscreen: nothing is
    // pressed and the cursor stays at (0, 0).
    virtual bool keyDown(Key key) const {
        (void)key;
        return false;
    }
    virtual bool mouseButtonDown(MouseButton button) const {
        (void)button;
        return false;
    }
    virtual CursorPosition cursorPosition() const { return {}; }

    // GL_VERSION and GL_RENDERER of the current context.
    std::string glVersion() const;
    std::string glRenderer() const;
};

// Thrown when a platform cannot give a context (library absent, no display, too old a GL).
class PlatformUnavailable : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

// A W x H offscreen context. Auto tries EGL, then OSMesa; if neither works, throws
// PlatformUnavailable with each platform's reason on one line.
std::unique_ptr<Platform> createOffscreenPlatform(Backend backend, int width, int height);

std::unique_ptr<Platform> createEglPlatform(int width, int height);
std::unique_ptr<Platform> createOsMesaPlatform(int width, int height);
std::unique_ptr<Platform> createGlfwPlatform(int width, int height, const std::string& title,
                                             bool visible);

// Loads GL 4.5 core entry points for the current context through `getProcAddress`; throws
// PlatformUnavailable naming `platform` if the context lacks GL 4.5 core.
using GlProc = void (*)();
void loadGl(GlProc (*getProcAddress)(const char* name), const char* platform);

}  // namespace amb
