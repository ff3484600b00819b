// Platform_test.cpp — each offscreen platform gives a GL 4.5 core context that renders into a
// framebuffer object; each test skips with the reason when its platform is absent.
#include "app/platform/Platform.h"

#include <gtest/gtest.h>

#include "app/render/Gl.h"
#include "world/Error.h"

namespace amb {
namespace {

// Clears an RGBA8 framebuffer object to a known colour and reads it back.
void expectClearReadsBack(Platform& platform) {
    const int w = platform.width(), h = platform.height();
    GlTexture colour = makeTexture2D(GL_RGBA8, w, h);
    GLuint fbo = 0;
    glCreateFramebuffers(1, &fbo);
    GlFramebuffer owner(fbo);
    glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT0, colour.id(), 0);
    ASSERT_EQ(glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER), GLenum(GL_FRAMEBUFFER_COMPLETE));
    const float c[4] = {0.25f, 0.5f, 1.0f, 1.0f};
    glClearNamedFramebufferfv(fbo, GL_COLOR, 0, c);
    const auto rgb = readPixelsRgb8(fbo, w, h);
    ASSERT_EQ(rgb.size(), size_t(w) * h * 3);
    // 8-bit quantisation: 0.25 * 255 = 63.75, so 63 or 64.
    EXPECT_NEAR(rgb[0], 64, 1);
    EXPECT_NEAR(rgb[1], 128, 1);
    EXPECT_EQ(rgb[2], 255);
    EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
}

TEST(Platform, EglGivesCore45Context) {
    std::unique_ptr<Platform> p;
    try {
        p = createEglPlatform(64, 32);
    } catch (const PlatformUnavailable& e) {
        GTEST_SKIP() << e.what();
    }
    EXPECT_EQ(p->backend(), Backend::Egl);
    EXPECT_FALSE(p->glVersion().empty());
    GLint profile = 0;
    glGetIntegerv(GL_CONTEXT_PROFILE_MASK, &profile);
    EXPECT_TRUE(profile & GL_CONTEXT_CORE_PROFILE_BIT);
    expectClearReadsBack(*p);
}

TEST(Platform, OsMesaGivesCore45Context) {
    std::unique_ptr<Platform> p;
    try {
        p = createOsMesaPlatform(64, 32);
    } catch (const PlatformUnavailable& e) {
        GTEST_SKIP() << e.what();
    }
    EXPECT_EQ(p->backend(), Backend::OsMesa);
    EXPECT_FALSE(p->glRenderer().empty());
    expectClearReadsBack(*p);
}

// The viewer reads its keys and mouse through the platform (Platform::keyDown ...): an offscreen
// platform has no window, so nothing is ever pressed and the cursor stays at the origin.
TEST(Platform, OffscreenHasNoKeyboardOrMouse) {
    std::unique_ptr<Platform> p;
    try {
        p = createOffscreenPlatform(Backend::Auto, 16, 16);
    } catch (const PlatformUnavailable& e) {
        GTEST_SKIP() << e.what();
    }
    p->pollEvents();
    for (int k = 0; k < kKeyCount; ++k) EXPECT_FALSE(p->keyDown(Key(k))) << "key " << k;
    EXPECT_FALSE(p->mouseButtonDown(MouseButton::Left));
    EXPECT_FALSE(p->mouseButtonDown(MouseButton::Right));
    EXPECT_EQ(p->cursorPosition().x, 0.0);
    EXPECT_EQ(p->cursorPosition().y, 0.0);
    EXPECT_EQ(p->nativeWindow(), nullptr);
}

TEST(Platform, AutoFallsBackAndRejectsBadSizes) {
    EXPECT_THROW(createOffscreenPlatform(Backend::Auto, 0, 0), InputError);
    EXPECT_THROW(parseBackend("vulkan", "--backend"), InputError);
    EXPECT_EQ(parseBackend("osmesa", "--backend"), Backend::OsMesa);
}

}  // namespace
}  // namespace amb
