// Renderer.cpp — ambient sources and one frame of the main view.
#include "app/render/Renderer.h"

#include <chrono>
#include <cmath>
#include <stdexcept>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/matrix.hpp>

#include "lighting/SH.h"
#include "world/Error.h"
#include "world/World.h"

namespace amb {

// ---- Renderer --------------------------------------------------------------------------------

static GlFramebuffer makeFramebuffer(GLuint colour, GLuint depth) {
    GLuint fbo = 0;
    glCreateFramebuffers(1, &fbo);
    glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT0, colour, 0);
    if (depth) glNamedFramebufferTexture(fbo, GL_DEPTH_ATTACHMENT, depth, 0);
    if (glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
        glDeleteFramebuffers(1, &fbo);
        throw std::runtime_error("renderer: incomplete framebuffer");
    }
    return GlFramebuffer(fbo);
}

Renderer::Renderer(const World& world, const RenderSettings& settings)
    : world_(world),
      settings_(settings),
      noon_(evaluateSky(world.sky(), 12.0)),
      exposure_(settings.exposure, exposureFor(noon_, noon_)),
      meter_(std::max(settings.width, 1), std::max(settings.height, 1)) {
    if (settings.width <= 0 || settings.height <= 0 || settings.width > 16384 ||
        settings.height > 16384) {
        throw InputError("--size", "image size must be between 1x1 and 16384x16384");
    }
    GLint maxSize = 0;
    glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &maxSize);
    if (settings.width > maxSize || settings.height > maxSize) {
        throw InputError(
            "--size", "image size exceeds the GL limit of " + std::to_string(maxSize) + " pixels");
    }
    drawer_ = std::make_unique<SceneDrawer>();
    RendererSceneSettings scene = settings.scene;
    scene.pixelsPerRadian = settings.height / settings.fovY_rad;
    scene_ = std::make_unique<RendererScene>(world, scene);
    hdr_ = makeTexture2D(GL_RGBA16F, settings.width, settings.height);
    depth_ = makeTexture2D(GL_DEPTH_COMPONENT32F, settings.width, settings.height);
    ldr_ = makeTexture2D(GL_RGBA8, settings.width, settings.height);
    hdrFbo_ = makeFramebuffer(hdr_.id(), depth_.id());
    ldrFbo_ = makeFramebuffer(ldr_.id(), 0);
    glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
    checkShadowSettings(settings.shadows, "shadow settings");
    if (settings.shadows.enabled)
        shadowMap_ = std::make_unique<ShadowMap>(
            settings.shadows.cascades + 1 + (settings.shadows.farDistance_m > 0.0 ? 1 : 0),
            settings.shadows.mapSize);  // + the car's, + the far cascade
}

Renderer::~Renderer() = default;

const SkyLighting& Renderer::setTimeOfDay(double timeOfDay_h) {
    if (timeOfDay_h != sky_.timeOfDay_h) {
        sky_ = evaluateSky(world_.sky(), timeOfDay_h);
        drawer_->setSky(sky_);
    }
    return sky_;
}

glm::mat4 Renderer::viewProjection(const CameraSample& camera) const {
    // Camera-relative view: the eye at the origin, so only rotation in the view matrix.
    const glm::vec3 f = glm::normalize(glm::vec3(camera.forward));
    const glm::vec3 up = glm::normalize(glm::vec3(camera.up));
    const glm::mat4 view = glm::lookAt(glm::vec3(0.0f), f, up);
    const float aspect = float(settings_.width) / float(settings_.height);
    return reversedInfinitePerspective(settings_.fovY_rad, aspect, settings_.near_m) * view;
}

ShadowBinding Renderer::renderShadows(const CameraSample& camera, RenderStats& stats) {
    ShadowBinding binding;
    if (!shadowMap_) return binding;
    const ShadowSettings& ss = settings_.shadows;
    const int n = ss.cascades;
    const glm::dvec3 f = glm::normalize(camera.forward);
    const double tanY = std::tan(0.5 * settings_.fovY_rad);
    const double tanX = tanY * double(settings_.width) / double(settings_.height);
    bool rendered = false;
    for (int k = 0; k < n; ++k) {
        const double near = k == 0 ? double(settings_.near_m) : cascadeFar_m(ss, k - 1, n);
        const auto [along, radius] = frustumSliceSphere(near, cascadeFar_m(ss, k, n), tanX, tanY);
        const glm::dvec3 centre = camera.position_m + along * f;
        if (shadowMap_->fitted(k)) {
            // A cascade of static casters is fixed in the world: it stays right wherever it
            // lies, so it is re-rendered only when the slice's sphere leaves it or the light
            // turns by 1 degree, and at most one a frame, the nearest first (the others keep
            // serving what they cover meanwhile).
            const bool inside = glm::length(centre - shadowMap_->centre(k)) + radius <=
                                shadowMap_->radius(k);
            const bool turned = glm::dot(shadowMap_->towardLight(k), sky_.lightDir) < 0.99985f;
            if (rendered || (inside && !turned)) continue;
        }
        const double margin = k == 0 ? ss.nearMargin : ss.staticMargin;
        shadowMap_->fit(k, centre, radius * (1.0 + margin), sky_.lightDir);
        scene_->buildCasters(camera.position_m, shadowMap_->casterViewProj(k, camera.position_m),
                             shadowMap_->texel_m(k), casters_, false);
        timer_.begin(RenderPass::ShadowCascades);
        const std::size_t triangles = shadowMap_->render(k, *drawer_, casters_, camera.position_m);
        timer_.end(triangles);
        stats.shadowTriangles += triangles;
        rendered = true;
    }
    binding.texture = shadowMap_->texture();
    binding.constants = shadowMap_->constants(camera.position_m, n, ss.pcf,
                                              ss.normalOffset_texels, ss.depthBias_texels);
    // The far terrain cascade: terrain and roads only, around the camera, re-rendered when the
    // camera leaves it or the light turns.
    if (ss.farDistance_m > 0.0) {
        const int far = n + 1;
        const bool inside = shadowMap_->fitted(far) &&
                            glm::length(camera.position_m - shadowMap_->centre(far)) +
                                    ss.farDistance_m <= shadowMap_->radius(far);
        const bool turned = !shadowMap_->fitted(far) ||
                            glm::dot(shadowMap_->towardLight(far), sky_.lightDir) < 0.99985f;
        if (!inside || turned) {
            shadowMap_->fit(far, camera.position_m, ss.farDistance_m * (1.0 + ss.staticMargin),
                            sky_.lightDir);
            scene_->buildCasters(camera.position_m,
                                 shadowMap_->casterViewProj(far, camera.position_m),
                                 shadowMap_->texel_m(far), casters_, false, false);
            timer_.begin(RenderPass::ShadowFar);
            const std::size_t triangles =
                shadowMap_->render(far, *drawer_, casters_, camera.position_m);
            timer_.end(triangles);
            stats.shadowTriangles += triangles;
        }
        shadowMap_->setSlot(binding.constants, kFarShadowSlot, far, camera.position_m,
                            ss.normalOffset_texels, ss.depthBias_texels, 0.0);
        binding.constants.far.x = 1.0f;
    }
    // The car, the one caster that moves: its own small map around it, every frame, with the
    // static casters around it, so that where it covers a receiver it is the one map read.
    if (const auto& car = scene_->vehicle()) {
        shadowMap_->fit(n, car->position_m, ss.carShadowRadius_m, sky_.lightDir, ss.carMapSize);
        scene_->buildCasters(camera.position_m, shadowMap_->casterViewProj(n, camera.position_m),
                             shadowMap_->texel_m(n), casters_, true);
        timer_.begin(RenderPass::ShadowCar);
        const std::size_t triangles = shadowMap_->render(n, *drawer_, casters_, camera.position_m);
        timer_.end(triangles);
        stats.shadowTriangles += triangles;
        shadowMap_->setSlot(binding.constants, kCarShadowSlot, n, camera.position_m,
                            ss.normalOffset_texels, ss.depthBias_texels, 0.0);
        binding.constants.params.w = 1.0f;
    }
    return binding;
}

RenderStats Renderer::render(const CameraSample& camera, const AmbientSource& ambient,
                             RenderOutput output) {
    using Clock = std::chrono::steady_clock;
    RenderStats stats;
    timer_.setEnabled(settings_.passTiming);
    timer_.startFrame();
    drawer_->setPassTimer(settings_.passTiming ? &timer_ : nullptr);
    const auto t0 = Clock::now();
    FrameConstants fc;
    fc.viewProj = viewProjection(camera);
    fc.invViewProj = glm::inverse(fc.viewProj);
    fillSkyConstants(sky_, fc);
    fc.fog = glm::vec4(settings_.fogExtinction_perM, 0.0f, float(int(output)), 0.0f);

    SceneStats ss;
    scene_->buildView(camera.position_m, fc.viewProj, ambient, list_, &ss);
    const auto t1 = Clock::now();
    const ShadowBinding shadows = renderShadows(camera, stats);
    const auto t1s = Clock::now();

    glBindFramebuffer(GL_FRAMEBUFFER, hdrFbo_.id());
    glViewport(0, 0, settings_.width, settings_.height);
    const float black[4] = {0, 0, 0, 0};
    const float far = 0.0f;
    glClearNamedFramebufferfv(hdrFbo_.id(), GL_COLOR, 0, black);
    glClearNamedFramebufferfv(hdrFbo_.id(), GL_DEPTH, 0, &far);
    stats.triangles = drawer_->draw(list_, fc, true, false, &shadows);

    if (output == RenderOutput::Shaded || output == RenderOutput::Ambient) {
        glBindFramebuffer(GL_FRAMEBUFFER, ldrFbo_.id());
        const float exposure = adaptExposure();
        timer_.begin(RenderPass::Tonemap);
        drawer_->drawTonemap(hdr_.id(), exposure);
        timer_.end(1);
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    const auto t2 = Clock::now();
    drawer_->setPassTimer(nullptr);
    stats.passesTimed = timer_.enabled();
    if (stats.passesTimed) stats.passes = timer_.passes();

    stats.terrainPatches = ss.terrainPatches;
    stats.terrainPatchesDrawn = ss.terrainPatchesDrawn;
    stats.objectsDrawn = ss.objectsDrawn;
    stats.terrainRebuilt = ss.terrainRebuilt;
    stats.terrainPatchesVertex = ss.terrainPatchesVertex;
    stats.terrainPatchesWaiting = ss.terrainPatchesWaiting;
    stats.scene_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
    stats.draw_ms = std::chrono::duration<double, std::milli>(t2 - t1).count();
    stats.shadow_ms = std::chrono::duration<double, std::milli>(t1s - t1).count();
    return stats;
}

std::vector<unsigned char> Renderer::readRgb8() {
    return readPixelsRgb8(ldrFbo_.id(), settings_.width, settings_.height);
}

std::vector<float> Renderer::readHdr() {
    const int w = settings_.width, h = settings_.height;
    std::vector<float> gl = readPixelsRgb32f(hdrFbo_.id(), 0, 0, w, h);
    std::vector<float> out(gl.size());
    for (int y = 0; y < h; ++y) {
        std::copy_n(&gl[size_t(h - 1 - y) * w * 3], size_t(w) * 3, &out[size_t(y) * w * 3]);
    }
    return out;
}

std::vector<unsigned char> Renderer::tonemap(const std::vector<float>& hdrRgb) {
    const int w = settings_.width, h = settings_.height;
    if (hdrRgb.size() != std::size_t(w) * h * 3)
        throw std::invalid_argument("Renderer::tonemap: image size differs from the view's");
    std::vector<float> rgba(std::size_t(w) * h * 4, 0.0f);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const std::size_t src = (std::size_t(y) * w + x) * 3;
            const std::size_t dst = (std::size_t(h - 1 - y) * w + x) * 4;  // GL rows from the bottom
            for (int c = 0; c < 3; ++c) rgba[dst + c] = hdrRgb[src + c];
        }
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTextureSubImage2D(hdr_.id(), 0, 0, 0, w, h, GL_RGBA, GL_FLOAT, rgba.data());
    glBindFramebuffer(GL_FRAMEBUFFER, ldrFbo_.id());
    glViewport(0, 0, w, h);
    drawer_->drawTonemap(hdr_.id(), exposure_.exposure());
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    return readRgb8();
}

SurfaceImage Renderer::readSurface(const CameraSample& camera) {
    const int w = settings_.width, h = settings_.height;
    SurfaceImage out;
    out.width = w, out.height = h;
    std::vector<float> rgba(std::size_t(w) * h * 4), depth(std::size_t(w) * h);
    readFramebuffer(hdrFbo_.id(), 0, 0, w, h, GL_RGBA, GL_FLOAT, 4, rgba.data());
    readFramebuffer(hdrFbo_.id(), 0, 0, w, h, GL_DEPTH_COMPONENT, GL_FLOAT, 4, depth.data());
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    const glm::mat4 inv = glm::inverse(viewProjection(camera));
    out.rgba.resize(rgba.size());
    out.position.assign(std::size_t(w) * h, glm::vec3(0.0f));
    for (int y = 0; y < h; ++y) {
        const int glRow = h - 1 - y;
        std::copy_n(&rgba[std::size_t(glRow) * w * 4], std::size_t(w) * 4,
                    &out.rgba[std::size_t(y) * w * 4]);
        for (int x = 0; x < w; ++x) {
            const std::size_t src = std::size_t(glRow) * w + x;
            if (!(rgba[4 * src + 3] > 0.0f)) continue;
            // Pixel centre in clip space; depth in [0, 1] (glClipControl zero-to-one).
            const glm::vec4 clip(2.0f * (float(x) + 0.5f) / float(w) - 1.0f,
                                 2.0f * (float(glRow) + 0.5f) / float(h) - 1.0f, depth[src], 1.0f);
            const glm::vec4 p = inv * clip;
            out.position[std::size_t(y) * w + x] = glm::vec3(p) / p.w;
        }
    }
    return out;
}

void Renderer::replaceLdr(const std::vector<unsigned char>& rgb) {
    // rgb is top row first; GL rows start at the bottom.
    const std::size_t row = std::size_t(settings_.width) * 3;
    if (rgb.size() != row * std::size_t(settings_.height)) return;
    std::vector<unsigned char> flipped(rgb.size());
    for (int y = 0; y < settings_.height; ++y)
        std::copy_n(&rgb[std::size_t(settings_.height - 1 - y) * row], row, &flipped[std::size_t(y) * row]);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTextureSubImage2D(ldr_.id(), 0, 0, 0, settings_.width, settings_.height, GL_RGB,
                        GL_UNSIGNED_BYTE, flipped.data());
}

void Renderer::blitToWindow(int windowWidth, int windowHeight) {
    glBlitNamedFramebuffer(ldrFbo_.id(), 0, 0, 0, settings_.width, settings_.height, 0, 0,
                           windowWidth, windowHeight, GL_COLOR_BUFFER_BIT, GL_LINEAR);
}

RenderOutput parseViewOutput(const std::string& name, const std::string& option) {
    if (name == "shaded") return RenderOutput::Shaded;
    if (name == "ambient") return RenderOutput::Ambient;
    throw InputError(option, "unknown view '" + name + "' (expected shaded or ambient)");
}

void Renderer::setViewState(const ViewState& state) {
    viewState_ = state;
    scene_->setVehicle(state.vehicle);
}

float Renderer::adaptExposure() {
    if (!settings_.exposure.enabled) return exposure_.hold(exposureFor(sky_, noon_));
    return exposure_.update(viewState_.time_s, sky_.timeOfDay_h, viewState_.cut, [&] {
        timer_.begin(RenderPass::Exposure);
        const double logMean = meter_.logMeanLuminance(hdrFbo_.id());
        timer_.end(0);
        glBindFramebuffer(GL_FRAMEBUFFER, ldrFbo_.id());
        return logMean;
    });
}

RenderStats Renderer::drawView(const CameraSample& camera, const AmbientSource& ambient) {
    const RenderStats stats = render(camera, ambient, settings_.viewOutput);
    glFinish();
    return stats;
}

}  // namespace amb
