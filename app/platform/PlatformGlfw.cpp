// PlatformGlfw.cpp — a window with a GL 4.5 core context through GLFW (X11; Xvfb in tests).
#include <glad/gl.h>
// GLFW after glad (GLFW_INCLUDE_NONE is set: it brings no GL header of its own).
#include <GLFW/glfw3.h>

#include "app/platform/Platform.h"

namespace amb {
namespace {

int glfwKey(Key key) {
    switch (key) {
        case Key::W: return GLFW_KEY_W;
        case Key::A: return GLFW_KEY_A;
        case Key::S: return GLFW_KEY_S;
        case Key::D: return GLFW_KEY_D;
        case Key::Q: return GLFW_KEY_Q;
        case Key::E: return GLFW_KEY_E;
        case Key::LeftShift: return GLFW_KEY_LEFT_SHIFT;
        case Key::Escape: return GLFW_KEY_ESCAPE;
        case Key::Tab: return GLFW_KEY_TAB;
        case Key::F: return GLFW_KEY_F;
        case Key::Space: return GLFW_KEY_SPACE;
        case Key::Left: return GLFW_KEY_LEFT;
        case Key::Right: return GLFW_KEY_RIGHT;
        case Key::LeftBracket: return GLFW_KEY_LEFT_BRACKET;
        case Key::RightBracket: return GLFW_KEY_RIGHT_BRACKET;
        case Key::R: return GLFW_KEY_R;
        case Key::P: return GLFW_KEY_P;
    }
    return GLFW_KEY_UNKNOWN;
}

class PlatformGlfw final : public Platform {
  public:
    PlatformGlfw(int width, int height, const std::string& title, bool visible) {
        if (!glfwInit()) throw PlatformUnavailable("glfw: cannot initialise (no display?)");
        glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
        glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
        glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
        glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
        glfwWindowHint(GLFW_VISIBLE, visible ? GLFW_TRUE : GLFW_FALSE);
        glfwWindowHint(GLFW_DEPTH_BITS, 0);
        window_ = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
        if (!window_) {
            glfwTerminate();
            throw PlatformUnavailable("glfw: no window with a GL 4.5 core context");
        }
        glfwMakeContextCurrent(window_);
        glfwSwapInterval(0);
        try {
            loadGl(reinterpret_cast<GlProc (*)(const char*)>(&glfwGetProcAddress), "glfw");
        } catch (...) {
            glfwDestroyWindow(window_);
            glfwTerminate();
            throw;
        }
    }
    ~PlatformGlfw() override {
        glfwDestroyWindow(window_);
        glfwTerminate();
    }

    Backend backend() const override { return Backend::Glfw; }
    bool hasWindow() const override { return true; }
    int width() const override {
        int w = 0, h = 0;
        glfwGetFramebufferSize(window_, &w, &h);
        return w;
    }
    int height() const override {
        int w = 0, h = 0;
        glfwGetFramebufferSize(window_, &w, &h);
        return h;
    }
    void swapBuffers() override { glfwSwapBuffers(window_); }
    void pollEvents() override { glfwPollEvents(); }
    bool shouldClose() const override { return glfwWindowShouldClose(window_); }
    void* nativeWindow() const override { return window_; }
    bool keyDown(Key key) const override {
        const int k = glfwKey(key);
        return k != GLFW_KEY_UNKNOWN && glfwGetKey(window_, k) == GLFW_PRESS;
    }
    bool mouseButtonDown(MouseButton button) const override {
        const int b = button == MouseButton::Left ? GLFW_MOUSE_BUTTON_LEFT : GLFW_MOUSE_BUTTON_RIGHT;
        return glfwGetMouseButton(window_, b) == GLFW_PRESS;
    }
    CursorPosition cursorPosition() const override {
        CursorPosition c;
        glfwGetCursorPos(window_, &c.x, &c.y);
        return c;
    }

  private:
    GLFWwindow* window_ = nullptr;
};

}  // namespace

std::unique_ptr<Platform> createGlfwPlatform(int width, int height, const std::string& title,
                                             bool visible) {
    return std::make_unique<PlatformGlfw>(width, height, title, visible);
}

}  // namespace amb
