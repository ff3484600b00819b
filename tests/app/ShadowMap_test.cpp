// ShadowMap_test.cpp — the shadow of the main light: a sphere over a plane casts the ellipse of
// the closed form (centre and axes within stated pixels); the frustum slice's sphere encloses
// the slice; texel snapping keeps a world point on the same place in its texel as the camera
// moves; settings and the --shadows switch refuse bad input.
#include "app/render/ShadowMap.h"

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "GlTestContext.h"
#include "world/Conventions.h"
#include "world/Error.h"

namespace amb {
namespace {

// A flat square of side 2 half_m at y = 0, n x n quads, normal up.
WorldMesh planeMesh(double half_m, int n, float albedo) {
    WorldMesh m;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
            const float x = float(-half_m + 2.0 * half_m * i / n);
            const float z = float(-half_m + 2.0 * half_m * j / n);
            m.positions.insert(m.positions.end(), {x, 0.0f, z});
            m.normals.insert(m.normals.end(), {0.0f, 1.0f, 0.0f});
            m.albedo.insert(m.albedo.end(), {albedo, albedo, albedo});
        }
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const std::uint32_t a = std::uint32_t(j * (n + 1) + i), b = a + 1,
                                c = a + std::uint32_t(n + 1), d = c + 1;
            // Counter-clockwise seen from above (+Y).
            m.indices.insert(m.indices.end(), {a, c, b, b, c, d});
        }
    return m;
}

// A UV sphere of radius r about the origin.
WorldMesh sphereMesh(float r, int slices, int stacks) {
    WorldMesh m;
    for (int j = 0; j <= stacks; ++j) {
        const double theta = kPi * j / stacks;
        for (int i = 0; i <= slices; ++i) {
            const double phi = 2.0 * kPi * i / slices;
            const glm::vec3 n(float(std::sin(theta) * std::cos(phi)), float(std::cos(theta)),
                              float(std::sin(theta) * std::sin(phi)));
            m.positions.insert(m.positions.end(), {r * n.x, r * n.y, r * n.z});
            m.normals.insert(m.normals.end(), {n.x, n.y, n.z});
            m.albedo.insert(m.albedo.end(), {0.5f, 0.5f, 0.5f});
        }
    }
    for (int j = 0; j < stacks; ++j)
        for (int i = 0; i < slices; ++i) {
            const std::uint32_t a = std::uint32_t(j * (slices + 1) + i), b = a + 1,
                                c = a + std::uint32_t(slices + 1), d = c + 1;
            m.indices.insert(m.indices.end(), {a, b, c, b, d, c});
        }
    return m;
}

// A sphere of radius 1 m with its centre 4 m over a plane, the light at elevation 40 degrees and
// azimuth 30 degrees (east of north, -Z). The shadow on the plane is the light's cylinder of
// radius R through the sphere cut by the plane: an ellipse centred on the sphere's centre moved
// along -L down to the plane (C - L h / L.y), semi-axes R across the light's azimuth and
// R / sin(elevation) along it. Seen from 20 m straight above the ellipse's centre at 256 x 256
// pixels (9 cm a pixel), the shadowed pixels' centroid must lie within 1 pixel of the centre
// and the axes from their second moments (a uniform ellipse has variance a^2 / 4 along a
// semi-axis a) within 1.5 pixels of the closed form; the major axis points along the light's
// azimuth within 3 degrees. One cascade of 1024^2 over 12 m (2.3 cm texels), PCF 2 x 2.
TEST(ShadowMap, SphereOverPlaneCastsTheClosedFormEllipse) {
    constexpr int kSize = 256;
    AMB_REQUIRE_PLATFORM(platform, Backend::Auto, kSize, kSize);
    const double elevation = 40.0 * kPi / 180.0, azimuth = 30.0 * kPi / 180.0;
    const glm::dvec3 L(std::cos(elevation) * std::sin(azimuth), std::sin(elevation),
                       -std::cos(elevation) * std::cos(azimuth));
    const double R = 1.0, h = 4.0;
    const glm::dvec3 sphere(0.0, h, 0.0);
    const glm::dvec3 centre = sphere - L * (h / L.y);  // the ellipse's centre on the plane
    const double minor = R, major = R / std::sin(elevation);
    const glm::dvec3 eye = centre + glm::dvec3(0.0, 20.0, 0.0);

    SceneDrawer drawer;
    const GlMesh plane = uploadMesh(planeMesh(30.0, 60, 0.5f));
    const GlMesh ball = uploadMesh(sphereMesh(float(R), 48, 24));
    DrawList list;
    TerrainDraw t;
    t.mesh = &plane;
    t.origin = glm::vec3(-eye);
    t.rect = glm::vec4(-30, -30, 1.0f / 60, 1.0f / 60);
    for (auto& c : t.cornerIrradiance) c = glm::vec3(1.0f);
    list.terrain.push_back(t);
    ObjectInstance inst;
    inst.positionScale = glm::vec4(glm::vec3(sphere - eye), 1.0f);
    list.objects.push_back({&ball, {inst}});
    list.ambientSets.emplace_back();

    ShadowMap map(1, 1024);
    map.fit(0, glm::dvec3(0.0, 2.0, 0.0) + 0.5 * (centre - glm::dvec3(0, 2, 0)), 12.0,
            glm::vec3(L));
    map.render(0, drawer, list, eye);
    ShadowBinding shadows;
    shadows.texture = map.texture();
    shadows.constants = map.constants(eye, 1, 2, 1.5, 1.0);

    GlTexture colour = makeTexture2D(GL_RGBA32F, kSize, kSize);
    GlTexture depth = makeTexture2D(GL_DEPTH_COMPONENT32F, kSize, kSize);
    GLuint fboId = 0;
    glCreateFramebuffers(1, &fboId);
    GlFramebuffer fbo(fboId);
    glNamedFramebufferTexture(fboId, GL_COLOR_ATTACHMENT0, colour.id(), 0);
    glNamedFramebufferTexture(fboId, GL_DEPTH_ATTACHMENT, depth.id(), 0);
    ASSERT_EQ(glCheckNamedFramebufferStatus(fboId, GL_FRAMEBUFFER), GLenum(GL_FRAMEBUFFER_COMPLETE));
    glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
    // Straight down; image up = -Z (north), image right = +X.
    const double fov = 60.0 * kPi / 180.0;
    FrameConstants fc;
    fc.viewProj = reversedInfinitePerspective(float(fov), 1.0f, 0.3f) *
                  glm::lookAt(glm::vec3(0.0f), glm::vec3(0, -1, 0), glm::vec3(0, 0, -1));
    fc.invViewProj = glm::inverse(fc.viewProj);
    fc.lightDir = glm::vec4(glm::vec3(L), 0.0f);
    fc.lightIrradiance = glm::vec4(10.0f);
    const auto renderWith = [&](float output) {
        fc.fog = glm::vec4(0.0f, 0.0f, output, 0.0f);
        glBindFramebuffer(GL_FRAMEBUFFER, fboId);
        glViewport(0, 0, kSize, kSize);
        const float black[4] = {0, 0, 0, 0}, far = 0.0f;
        glClearNamedFramebufferfv(fboId, GL_COLOR, 0, black);
        glClearNamedFramebufferfv(fboId, GL_DEPTH, 0, &far);
        drawer.draw(list, fc, false, false, &shadows);
        return readPixelsRgb32f(fboId, 0, 0, kSize, kSize);
    };
    const std::vector<float> shaded = renderWith(0.0f);
    // Lit plane: 0.5 / pi (1 + 10 sin(elevation)); in shadow 0.5 / pi. Threshold half way.
    const double lit = 0.5 / kPi * (1.0 + 10.0 * std::sin(elevation)), dark = 0.5 / kPi;
    const double threshold = 0.5 * (lit + dark);
    const double tanHalf = std::tan(0.5 * fov);
    const double metresPerPixel = 2.0 * 20.0 * tanHalf / kSize;
    double n = 0, sx = 0, sz = 0;
    std::vector<glm::dvec2> pts;
    for (int row = 0; row < kSize; ++row)
        for (int col = 0; col < kSize; ++col) {
            const float* p = &shaded[(std::size_t(row) * kSize + col) * 3];
            if (p[0] >= threshold) continue;
            // GL row 0 is the bottom: image bottom = +Z (south). Ground point under the pixel.
            const double u = (2.0 * (col + 0.5) / kSize - 1.0) * tanHalf;
            const double v = (2.0 * (row + 0.5) / kSize - 1.0) * tanHalf;
            const glm::dvec2 g(eye.x + 20.0 * u, eye.z - 20.0 * v);
            // The sphere itself is seen 5 m or more from the ellipse's centre: not ground.
            if (glm::length(g - glm::dvec2(centre.x, centre.z)) > 2.5 * major) continue;
            pts.push_back(g);
            n += 1, sx += g.x, sz += g.y;
        }
    ASSERT_GT(n, 200);
    const glm::dvec2 mean(sx / n, sz / n);
    EXPECT_LT(glm::length(mean - glm::dvec2(centre.x, centre.z)) / metresPerPixel, 1.0);
    // Axes from the covariance's eigenvalues.
    double cxx = 0, czz = 0, cxz = 0;
    for (const glm::dvec2& p : pts) {
        const glm::dvec2 d = p - mean;
        cxx += d.x * d.x, czz += d.y * d.y, cxz += d.x * d.y;
    }
    cxx /= n, czz /= n, cxz /= n;
    const double tr = cxx + czz, det = cxx * czz - cxz * cxz;
    const double l1 = 0.5 * tr + std::sqrt(0.25 * tr * tr - det), l2 = 0.5 * tr - std::sqrt(0.25 * tr * tr - det);
    EXPECT_NEAR(2.0 * std::sqrt(l1) / metresPerPixel, major / metresPerPixel, 1.5);
    EXPECT_NEAR(2.0 * std::sqrt(l2) / metresPerPixel, minor / metresPerPixel, 1.5);
    // The major axis along the light's azimuth (either sense).
    const glm::dvec2 axis = glm::normalize(glm::dvec2(cxz, l1 - cxx));
    const glm::dvec2 along = glm::normalize(glm::dvec2(L.x, L.z));
    EXPECT_GT(std::abs(glm::dot(axis, along)), std::cos(3.0 * kPi / 180.0));
    ::testing::Test::RecordProperty("shadowPixels", int(n));
    ::testing::Test::RecordProperty(
        "measured_px", "centre off by " +
                           std::to_string(glm::length(mean - glm::dvec2(centre.x, centre.z)) /
                                          metresPerPixel) +
                           ", major " + std::to_string(2.0 * std::sqrt(l1) / metresPerPixel) +
                           " (closed form " + std::to_string(major / metresPerPixel) +
                           "), minor " + std::to_string(2.0 * std::sqrt(l2) / metresPerPixel) +
                           " (" + std::to_string(minor / metresPerPixel) + ")");
}

// The bounding sphere of a frustum slice holds the slice's eight corners, and touches one.
TEST(ShadowMap, FrustumSliceSphereEnclosesTheSlice) {
    for (const auto& [n, f] : {std::pair{0.3, 12.5}, {12.5, 50.0}, {50.0, 200.0}, {1.0, 1.5}}) {
        const double tx = 1.0264, ty = 0.5774;
        const auto [c, r] = frustumSliceSphere(n, f, tx, ty);
        double farthest = 0.0;
        for (double z : {n, f})
            for (double sx : {-1.0, 1.0})
                for (double sy : {-1.0, 1.0}) {
                    const glm::dvec3 corner(sx * tx * z, sy * ty * z, z);
                    farthest = std::max(farthest, glm::length(corner - glm::dvec3(0, 0, c)));
                }
        EXPECT_LE(farthest, r * (1.0 + 1e-9)) << n << " " << f;
        EXPECT_GE(farthest, r * (1.0 - 1e-9)) << n << " " << f;
    }
}

// Texel snapping: as the cascade's centre moves by fractions of a texel, a fixed world point
// keeps its position within its texel (to 1e-3 texel), so the shadow does not crawl.
TEST(ShadowMap, SnappedCascadesKeepWorldPointsOnTheirTexels) {
    AMB_REQUIRE_PLATFORM(platform, Backend::Auto, 16, 16);
    ShadowMap map(1, 1024);
    const glm::vec3 light = glm::normalize(glm::vec3(0.3f, 0.8f, -0.4f));
    const glm::dvec3 point(1234.5, 210.0, -876.25);
    double first = -1.0;
    for (int step = 0; step < 10; ++step) {
        const glm::dvec3 eye(1200.0 + 0.37 * step, 205.0, -850.0 - 0.61 * step);
        map.fit(0, eye + glm::dvec3(3.0, 0.0, -7.0), 60.0, light);
        const ShadowConstants sc = map.constants(eye, 1, 1, 0.0, 0.0);
        const glm::vec4 uv = sc.matrix[0] * glm::vec4(glm::vec3(point - eye), 1.0f);
        const double texelX = uv.x * 1024.0;
        const double frac = texelX - std::floor(texelX);
        if (first < 0.0) first = frac;
        EXPECT_NEAR(frac, first, 1e-3) << "step " << step;
    }
}

TEST(ShadowMap, SettingsAndSwitchRefuseBadInput) {
    EXPECT_TRUE(parseShadowSwitch("on", "--shadows"));
    EXPECT_FALSE(parseShadowSwitch("off", "--shadows"));
    EXPECT_THROW(parseShadowSwitch("yes", "--shadows"), InputError);
    ShadowSettings s;
    EXPECT_NO_THROW(checkShadowSettings(s, "test"));
    s.cascades = 5;
    EXPECT_THROW(checkShadowSettings(s, "test"), InputError);
    s = {};
    s.pcf = 0;
    EXPECT_THROW(checkShadowSettings(s, "test"), InputError);
    s = {};
    s.distance_m = std::nan("");
    EXPECT_THROW(checkShadowSettings(s, "test"), InputError);
    s = {};
    EXPECT_NE(describeShadows(s).find("cascaded shadow maps: 3 x 512"), std::string::npos);
    s.enabled = s.captures = false;
    EXPECT_EQ(describeShadows(s), "none");
}

}  // namespace
}  // namespace amb
