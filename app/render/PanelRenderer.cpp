// PanelRenderer.cpp — Dear ImGui's GLFW and OpenGL 3 backends over the window (see
// PanelRenderer.h).
#include "app/render/PanelRenderer.h"

#include <algorithm>

#include "app/render/Gl.h"
// The backend's header after glad: the backend itself was built against glad's entry points.
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_opengl3.h>

#include "world/Error.h"

namespace amb {

PanelRenderer::PanelRenderer(void* window) {
    // The window's input first (installs its callbacks, chaining the window's own).
    ImGui_ImplGlfw_InitForOpenGL(static_cast<GLFWwindow*>(window), true);
    // GLSL 4.10 core and up take the backend's core shaders; the contexts here are 4.5 core.
    AMB_CHECK(ImGui_ImplOpenGL3_Init("#version 450 core"));
}

PanelRenderer::~PanelRenderer() {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
}

void PanelRenderer::newFrame() {
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
}

void PanelRenderer::draw(ImDrawData* data, int windowWidth, int windowHeight) {
    if (!data) return;
    // The backend saves and restores the GL state it changes, but draws into whatever is bound.
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, windowWidth, windowHeight);
    ImGui_ImplOpenGL3_RenderDrawData(data);
}

std::vector<unsigned char> readWindowRgb8(int width, int height) {
    std::vector<unsigned char> rgb(std::size_t(width) * height * 3), row(std::size_t(width) * 3);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    glReadBuffer(GL_BACK);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, rgb.data());
    // GL's rows run bottom up.
    for (int y = 0; y < height / 2; ++y) {
        unsigned char* a = &rgb[std::size_t(y) * width * 3];
        unsigned char* b = &rgb[std::size_t(height - 1 - y) * width * 3];
        std::copy_n(a, row.size(), row.data());
        std::copy_n(b, row.size(), a);
        std::copy_n(row.data(), row.size(), b);
    }
    return rgb;
}

}  // namespace amb
