// PanelRenderer.h — the window side of the tuning panel (app/cli/TuningPanel.h): Dear ImGui's
// GLFW backend (the window's keyboard and mouse for the panel) and OpenGL 3 backend (Debian's
// libimgui-dev, GL through glad), drawing the panel over the window's default framebuffer, and
// the window's pixels read back as the user sees them. The panel itself names neither GLFW nor GL.
#pragma once

#include <vector>

struct ImDrawData;

namespace amb {

class PanelRenderer {
  public:
    // Needs an ImGui context and the window's GL context current; `window` is the platform's
    // native window (Platform::nativeWindow, a GLFWwindow), whose input the panel then reads.
    explicit PanelRenderer(void* window);
    ~PanelRenderer();
    PanelRenderer(const PanelRenderer&) = delete;
    PanelRenderer& operator=(const PanelRenderer&) = delete;

    // Call before ImGui::NewFrame (the backend's font texture on the first frame, the window's
    // input and size).
    void newFrame();
    // Draws `data` into the default framebuffer of a window of that size (after the scene's
    // blit, before the swap).
    void draw(ImDrawData* data, int windowWidth, int windowHeight);
};

// The window's back buffer, top row first, RGB 8-bit (what the next swap shows).
std::vector<unsigned char> readWindowRgb8(int width, int height);

}  // namespace amb
