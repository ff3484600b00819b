// ShadowMap.cpp — settings, sphere fitting with texel snapping, the depth pass and the
// receivers' constants.
#include "app/render/ShadowMap.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include <glm/geometric.hpp>

#include "world/Error.h"

namespace amb {

// ---- [SECTION] ShadowSettings ----------------------------------------------------------------

void checkShadowSettings(const ShadowSettings& s, const std::string& where) {
    const auto need = [&](bool ok, const std::string& field, const std::string& what) {
        if (!ok) throw InputError(where, field + " " + what);
    };
    need(s.cascades >= 1 && s.cascades <= kMaxShadowCascades, "cascades", "must be 1 to 4");
    need(s.mapSize >= 64 && s.mapSize <= 8192, "map size", "must be 64 to 8192 texels");
    need(s.pcf >= 1 && s.pcf <= 3, "PCF", "must be 1, 2 or 3 taps per side");
    need(std::isfinite(s.distance_m) && s.distance_m >= 1.0 && s.distance_m <= 5000.0,
         "distance", "must be 1 to 5000 m");
    need(std::isfinite(s.staticMargin) && s.staticMargin >= 0.0 && s.staticMargin <= 2.0 &&
             std::isfinite(s.nearMargin) && s.nearMargin >= 0.0 && s.nearMargin <= 2.0,
         "cascade margins", "must be 0 to 2");
    need(s.farDistance_m == 0.0 || (std::isfinite(s.farDistance_m) &&
                                    s.farDistance_m > s.distance_m && s.farDistance_m <= 20000.0),
         "far cascade distance", "must be 0 (none) or beyond the cascades' end, up to 20000 m");
    need(s.carMapSize >= 16 && s.carMapSize <= s.mapSize, "car map size",
         "must be 16 to the map size");
    need(std::isfinite(s.carShadowRadius_m) && s.carShadowRadius_m >= 1.0 &&
             s.carShadowRadius_m <= 100.0,
         "car shadow radius", "must be 1 to 100 m");
    need(s.captureMapSize >= 64 && s.captureMapSize <= 8192, "capture map size",
         "must be 64 to 8192 texels");
    need(s.captureMaps >= 1 && s.captureMaps <= kMaxShadowLayers, "capture maps",
         "must be 1 to 16");
    need(std::isfinite(s.captureRegion_m) && s.captureRegion_m >= 10.0 &&
             s.captureRegion_m <= 5000.0,
         "capture region", "must be 10 to 5000 m");
    need(std::isfinite(s.captureRefresh_deg) && s.captureRefresh_deg > 0.0 &&
             s.captureRefresh_deg <= 90.0,
         "capture refresh angle", "must be in (0, 90] degrees");
    const bool biasesOk = std::isfinite(s.normalOffset_texels) && std::isfinite(s.depthBias_texels) &&
                          std::isfinite(s.captureBias_m) && s.normalOffset_texels >= 0.0 &&
                          s.depthBias_texels >= 0.0 && s.captureBias_m >= 0.0 &&
                          s.normalOffset_texels <= 100.0 && s.depthBias_texels <= 100.0 &&
                          s.captureBias_m <= 100.0;
    need(biasesOk, "biases", "must be finite, 0 to 100");
}

bool parseShadowSwitch(const std::string& text, const std::string& option) {
    if (text == "on") return true;
    if (text == "off") return false;
    throw InputError(option, "expected on or off, got '" + text + "'");
}

std::string describeShadows(const ShadowSettings& s) {
    std::ostringstream o;
    if (s.enabled) {
        o << "cascaded shadow maps: " << s.cascades << " x " << s.mapSize << "^2 to "
          << s.distance_m << " m, PCF " << s.pcf << "x" << s.pcf << " bilinear taps";
        o << ", static casters re-rendered when the view leaves a cascade (margins "
          << s.nearMargin << ", " << s.staticMargin << "), the car in its own " << s.carMapSize
          << "^2 map over " << s.carShadowRadius_m
          << " m (with the static casters there) every frame";
        if (s.farDistance_m > 0.0)
            o << ", terrain to " << s.farDistance_m << " m in a far cascade";
    } else {
        o << "main view: none";
    }
    if (s.captures) {
        o << "; captures: " << s.captureMaps << " maps of " << s.captureMapSize << "^2 over "
          << s.captureRegion_m << " m, refreshed after " << s.captureRefresh_deg << " deg";
    } else {
        o << "; captures: none";
    }
    if (!s.enabled && !s.captures) return "none";
    return o.str();
}

double cascadeFar_m(const ShadowSettings& s, int k, int n) {
    return s.distance_m / std::pow(4.0, double(n - 1 - k));
}

std::pair<double, double> frustumSliceSphere(double near_m, double far_m, double tanX,
                                             double tanY) {
    // The centre on the axis equidistant from the near and the far corners; no further than
    // the far plane (then the far corners alone bound the slice).
    const double t2 = tanX * tanX + tanY * tanY;
    const double c = std::min(0.5 * (near_m + far_m) * (1.0 + t2), far_m);
    const double r = std::sqrt((far_m - c) * (far_m - c) + far_m * far_m * t2);
    return {c, r};
}

// ---- [SECTION] ShadowMap ---------------------------------------------------------------------

ShadowMap::ShadowMap(int layers, int mapSize)
    : layers_(layers), size_(mapSize), cascades_(std::size_t(std::max(layers, 0))) {
    if (layers < 1 || layers > kMaxShadowLayers || mapSize < 1)
        throw std::invalid_argument("ShadowMap: bad layer count or size");
    GLuint tex = 0;
    glCreateTextures(GL_TEXTURE_2D_ARRAY, 1, &tex);
    depth_ = GlTexture(tex);
    // 16-bit depth: steps of 2 r / 65535 (9 mm across the 566 m of the last cascade), and half
    // the memory a software rasteriser's lookups walk through.
    glTextureStorage3D(tex, 1, GL_DEPTH_COMPONENT16, mapSize, mapSize, layers);
    glTextureParameteri(tex, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(tex, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(tex, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(tex, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTextureParameteri(tex, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    glTextureParameteri(tex, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
    for (int k = 0; k < layers; ++k) {
        GLuint fbo = 0;
        glCreateFramebuffers(1, &fbo);
        fbos_.emplace_back(fbo);
        glNamedFramebufferTextureLayer(fbo, GL_DEPTH_ATTACHMENT, tex, 0, k);
        glNamedFramebufferDrawBuffer(fbo, GL_NONE);
        glNamedFramebufferReadBuffer(fbo, GL_NONE);
        if (glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
            throw std::runtime_error("shadow map: incomplete framebuffer");
    }
}

void ShadowMap::fit(int k, const glm::dvec3& centre_m, double radius_m,
                    const glm::vec3& towardLight, int texels) {
    Cascade& c = cascades_[std::size_t(k)];
    c.texels = texels > 0 && texels < size_ ? texels : size_;
    c.light = glm::normalize(towardLight);
    c.ez = glm::dvec3(c.light);
    // A light frame that depends on the light alone (not on the camera), so the texel grid is
    // fixed in the world while the light stands still.
    const glm::dvec3 up = std::abs(c.ez.y) < 0.99 ? glm::dvec3(0, 1, 0) : glm::dvec3(0, 0, 1);
    c.ex = glm::normalize(glm::cross(up, c.ez));
    c.ey = glm::cross(c.ez, c.ex);
    c.radius_m = radius_m;
    // Snap the centre to whole texels across the light (along it, depth needs no snapping).
    const double texel = 2.0 * radius_m / c.texels;
    const double a = std::floor(glm::dot(centre_m, c.ex) / texel) * texel;
    const double b = std::floor(glm::dot(centre_m, c.ey) / texel) * texel;
    c.centre_m = a * c.ex + b * c.ey + glm::dot(centre_m, c.ez) * c.ez;
}

glm::mat4 ShadowMap::casterViewProj(int k, const glm::dvec3& eye_m) const {
    const Cascade& c = cascades_[std::size_t(k)];
    // p_rel + (eye - centre) = p - centre, in the light frame, scaled to the sphere: x, y in
    // [-1, 1]; depth 0 on the light side, 1 on the far side.
    const glm::dvec3 d = eye_m - c.centre_m;
    const double s = 1.0 / c.radius_m;
    glm::mat4 m(0.0f);
    for (int i = 0; i < 3; ++i) {
        m[i][0] = float(c.ex[i] * s);
        m[i][1] = float(c.ey[i] * s);
        m[i][2] = float(-c.ez[i] * 0.5 * s);
    }
    m[3][0] = float(glm::dot(d, c.ex) * s);
    m[3][1] = float(glm::dot(d, c.ey) * s);
    m[3][2] = float(0.5 - 0.5 * glm::dot(d, c.ez) * s);
    m[3][3] = 1.0f;
    return m;
}

std::size_t ShadowMap::render(int k, SceneDrawer& drawer, const DrawList& casters,
                              const glm::dvec3& eye_m) {
    const GLuint fbo = fbos_[std::size_t(k)].id();
    glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);  // depth in [0, 1], as every pass here
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    const int texels = cascades_[std::size_t(k)].texels;
    glViewport(0, 0, texels, texels);
    glEnable(GL_SCISSOR_TEST);  // a layer's corner is cleared and drawn alone
    glScissor(0, 0, texels, texels);
    const float one = 1.0f;
    glClearNamedFramebufferfv(fbo, GL_DEPTH, 0, &one);
    glEnable(GL_DEPTH_CLAMP);  // casters towards the light, beyond the sphere, at depth 0
    const std::size_t triangles = drawer.drawDepth(casters, casterViewProj(k, eye_m));
    glDisable(GL_DEPTH_CLAMP);
    glDisable(GL_SCISSOR_TEST);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    return triangles;
}

void ShadowMap::setSlot(ShadowConstants& sc, int slot, int k, const glm::dvec3& eye_m,
                        double normalOffset_texels, double depthBias_texels,
                        double extraBias_m) const {
    // Clip (x, y in [-1, 1]) to the cascade's texture coordinates [0, 1].
    glm::mat4 toUv(1.0f);
    toUv[0][0] = toUv[1][1] = 0.5f;
    toUv[3][0] = toUv[3][1] = 0.5f;
    sc.matrix[slot] = toUv * casterViewProj(k, eye_m);
    const Cascade& c = cascades_[std::size_t(k)];
    const double texel = texel_m(k);
    const double depthRange_m = 2.0 * c.radius_m;
    sc.offset[slot] = glm::vec4(float(normalOffset_texels * texel),
                                float((depthBias_texels * texel + extraBias_m) / depthRange_m),
                                float(k), float(c.texels) / float(size_));
}

ShadowConstants ShadowMap::constants(const glm::dvec3& eye_m, int count, int pcf,
                                     double normalOffset_texels, double depthBias_texels,
                                     double extraBias_m, int first) const {
    ShadowConstants sc;
    count = std::min({count, layers_ - first, kMaxShadowCascades});
    for (int slot = 0; slot < count; ++slot)
        setSlot(sc, slot, first + slot, eye_m, normalOffset_texels, depthBias_texels, extraBias_m);
    sc.params = glm::vec4(float(count), 1.0f / float(size_), float(pcf), 0.0f);
    return sc;
}

}  // namespace amb
