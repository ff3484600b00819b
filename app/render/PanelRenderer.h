// PanelRenderer.h — the GL side of the tuning panel (app/cli/TuningPanel.h): Dear ImGui's OpenGL 3
// backend (Debian's libimgui-dev, GL through glad), drawing the panel over the window's
// default framebuffer, and the window's pixels read back as the user sees them.
#pragma once

#include <vector>

struct ImDrawData;

namespace amb {

class PanelRenderer {
  public:
    // Needs an ImGui context and the window's GL context current.
    PanelRenderer();
    ~PanelRenderer();
    PanelRenderer(const PanelRenderer&) = delete;
    PanelRenderer& operator=(const PanelRenderer&) = delete;

    // Call before ImGui::NewFrame (the backend's font texture, on the first frame).
    void newFrame();
    // Draws `data` into the default framebuffer of a window of that size (after the scene's
    // blit, before the swap).
    void draw(ImDrawData* data, int windowWidth, int windowHeight);
};

// The window's back buffer, top row first, RGB 8-bit (what the next swap shows).
std::vector<unsigned char> readWindowRgb8(int width, int height);

}  // namespace amb
