// Renderer_test.cpp — the main view on EGL and OSMesa: sky above the horizon and terrain below by
// pixel statistics against the sky model, and the two platforms agree (PSNR >= 40 dB); road
// vertices are lit at their own positions and normals.
#include "app/render/Renderer.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "GlTestContext.h"
#include "app/render/RendererScene.h"
#include "lighting/SH.h"
#include "world/Conventions.h"
#include "world/Error.h"
#include "world/World.h"

namespace amb {
namespace {

constexpr int kW = 160, kH = 96;

// A camera 2 m above open ground, looking north and tilted by `pitch`.
CameraSample viewAt(const World& world, double pitch_rad) {
    CameraSample c;
    c.position_m = test::openGround(world) + glm::dvec3(0.0, 2.0, 0.0);
    c.forward = glm::dvec3(0.0, std::sin(pitch_rad), -std::cos(pitch_rad));
    c.up = glm::dvec3(0.0, std::cos(pitch_rad), std::sin(pitch_rad));
    return c;
}

RenderSettings testSettings() {
    RenderSettings rs;
    rs.width = kW;
    rs.height = kH;
    return rs;
}

struct Frame {
    std::vector<float> hdr;
    std::vector<unsigned char> ldr;
    SkyLighting sky;
};

Frame renderView(const World& world, double pitch_rad, double time_h) {
    RenderSettings rs;
    rs.width = kW;
    rs.height = kH;
    Renderer renderer(world, rs);
    Frame f;
    f.sky = renderer.setTimeOfDay(time_h);
    const FixedAmbient ambient(AmbientMode::Hemisphere, f.sky);
    renderer.render(viewAt(world, pitch_rad), ambient);
    f.hdr = renderer.readHdr();
    f.ldr = renderer.readRgb8();
    return f;
}

// Direction through the centre of pixel (x, y), y = 0 the top row, for the view above.
glm::dvec3 pixelDirection(const CameraSample& c, int x, int y) {
    const double tanHalf = std::tan(0.5 * 1.0471976);
    const double aspect = double(kW) / kH;
    const double sx = (2.0 * (x + 0.5) / kW - 1.0) * tanHalf * aspect;
    const double sy = (1.0 - 2.0 * (y + 0.5) / kH) * tanHalf;
    const glm::dvec3 right = glm::cross(c.forward, c.up);
    return glm::normalize(c.forward + sx * right + sy * c.up);
}

void expectSkyAboveTerrainBelow(Backend backend) {
    AMB_REQUIRE_PLATFORM(platform, backend, kW, kH);
    const World world(WorldSettings{});
    // Looking up 46 degrees: the top rows (64 to 76 degrees up) see only sky.
    {
        const double pitch = 0.8;
        const Frame f = renderView(world, pitch, 12.0);
        const CameraSample cam = viewAt(world, pitch);
        const SkyState state = world.sky().state(12.0);
        double maxRel = 0.0;
        int n = 0;
        for (int y = 0; y < kH / 5; ++y) {
            for (int x = 0; x < kW; x += 7) {
                const glm::dvec3 d = pixelDirection(cam, x, y);
                const glm::vec3 expected = world.sky().radiance(d, state);
                const float* got = &f.hdr[(size_t(y) * kW + x) * 3];
                for (int c = 0; c < 3; ++c) {
                    const double rel = std::abs(got[c] - expected[c]) / expected[c];
                    maxRel = std::max(maxRel, rel);
                }
                ++n;
            }
        }
        // The sky texture is 64 x 32 texels, bilinear; the model varies slowly away from the
        // sun (not in view here), so 10 % bounds the resampling error.
        EXPECT_LT(maxRel, 0.10) << "over " << n << " sky pixels";
    }
    // Looking down 35 degrees: the bottom rows see the ground, whose radiance is at most that of
    // a white Lambertian surface under the sun and the whole sky, and much less than the sky.
    {
        const double pitch = -0.6;
        const Frame f = renderView(world, pitch, 12.0);
        const glm::vec3 maxIrr = f.sky.lightIrradiance + f.sky.skyIrradianceUp * 2.0f;
        const float bound = (maxIrr.r + maxIrr.g + maxIrr.b) / float(kPi);
        double g = 0.0, b = 0.0;
        int above = 0;
        for (int y = kH - kH / 5; y < kH; ++y) {
            for (int x = 0; x < kW; ++x) {
                const float* p = &f.hdr[(size_t(y) * kW + x) * 3];
                if (p[0] + p[1] + p[2] > bound) ++above;
                g += p[1];
                b += p[2];
            }
        }
        EXPECT_EQ(above, 0) << "ground pixels brighter than a white Lambertian surface";
        // Grass: green over blue, unlike the sky (blue over green at noon).
        EXPECT_GT(g, b) << "the bottom band looks like sky";
        EXPECT_GT(g, 0.0);
    }
}

TEST(Renderer, EglSkyAboveTerrainBelow) {
    expectSkyAboveTerrainBelow(Backend::Egl);
}
TEST(Renderer, OsMesaSkyAboveTerrainBelow) {
    expectSkyAboveTerrainBelow(Backend::OsMesa);
}

double psnr(const std::vector<unsigned char>& a, const std::vector<unsigned char>& b) {
    double se = 0.0;
    for (size_t i = 0; i < a.size(); ++i) se += (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
    const double mse = se / double(a.size());
    return mse == 0.0 ? 99.0 : 10.0 * std::log10(255.0 * 255.0 / mse);
}

TEST(Renderer, EglAndOsMesaAgree) {
    const World world(WorldSettings{});
    std::vector<unsigned char> egl, osmesa;
    {
        AMB_REQUIRE_PLATFORM(platform, Backend::Egl, kW, kH);
        egl = renderView(world, -0.1, 16.0).ldr;
    }
    {
        AMB_REQUIRE_PLATFORM(platform, Backend::OsMesa, kW, kH);
        osmesa = renderView(world, -0.1, 16.0).ldr;
    }
    ASSERT_EQ(egl.size(), osmesa.size());
    EXPECT_GE(psnr(egl, osmesa), 40.0);
}

TEST(Renderer, RejectsAbsurdSizes) {
    AMB_REQUIRE_PLATFORM(platform, Backend::Auto, 16, 16);
    const World world(WorldSettings{});
    RenderSettings rs;
    rs.width = 100000;
    rs.height = 100000;
    EXPECT_THROW(Renderer(world, rs), InputError);
    rs.width = 0;
    rs.height = 0;
    EXPECT_THROW(Renderer(world, rs), InputError);
}

// An ambient that bends with x and z and turns with the normal; it counts the lookups made one
// at a time (the draw should batch them).
class CurvedAmbient final : public AmbientSource {
  public:
    static glm::vec3 field(const glm::dvec3& p, const glm::dvec3& n) {
        return glm::vec3(float(1.0 + 0.3 * std::sin(p.x / 37.0)),
                         float(1.0 + 0.3 * std::cos(p.z / 23.0)), float(1.0 + 2.0 * (n.x + n.z)));
    }
    glm::vec3 cornerIrradiance(const glm::dvec3& p, const glm::dvec3& n) const override {
        ++singles;
        return field(p, n);
    }
    void cornerIrradianceBatch(std::size_t count, const glm::dvec3* p, const glm::dvec3* n,
                               glm::vec3* out, const double* = nullptr) const override {
        for (std::size_t i = 0; i < count; ++i) out[i] = field(p[i], n[i]);
    }
    std::uint32_t objectSet(const glm::dvec3&, std::vector<AmbientSet>& sets) const override {
        sets.emplace_back();
        return std::uint32_t(sets.size() - 1);
    }
    mutable int singles = 0;
};

template <class T>
std::vector<T> readBack(const GlBuffer& buffer) {
    GLint bytes = 0;
    glGetNamedBufferParameteriv(buffer.id(), GL_BUFFER_SIZE, &bytes);
    std::vector<T> out(std::size_t(bytes) / sizeof(T));
    glGetNamedBufferSubData(buffer.id(), 0, bytes, out.data());
    return out;
}

// Looking down onto the steepest stretch of the mountain road: each road vertex is lit by the
// ambient at its own position with its own (tilted) normal, through the batch, so the colour
// follows the field along the road and differs from the old lighting (the chunk's bounding-box
// corners with an up normal, bilinear).
TEST(Renderer, RoadsAreLitAtTheirOwnVerticesAndNormals) {
    AMB_REQUIRE_PLATFORM(platform, Backend::Auto, kW, kH);
    const World world(WorldSettings{});
    const auto& c = world.roads().find("mountain")->centreline;
    std::size_t steep = 24;
    for (std::size_t i = 24; i + 24 < c.size(); i += 8) {
        if (std::abs(c[i + 24].y - c[i - 24].y) > std::abs(c[steep + 24].y - c[steep - 24].y))
            steep = i;
    }
    const glm::dvec3 target = c[steep];
    const glm::dvec3 eye = target + glm::dvec3(0.0, 80.0, 40.0);
    const glm::vec3 forward = glm::normalize(glm::vec3(target - eye));
    const glm::vec3 right = glm::normalize(glm::cross(forward, glm::vec3(0, 1, 0)));
    const glm::mat4 viewProj = reversedInfinitePerspective(1.0471976f, float(kW) / kH, 0.1f) *
                               glm::lookAt(glm::vec3(0.0f), forward, glm::cross(right, forward));
    RendererScene scene(world);
    DrawList list;
    const CurvedAmbient ambient;
    scene.buildView(eye, viewProj, ambient, list);
    EXPECT_EQ(ambient.singles, 0);

    int roadDraws = 0, targetChunks = 0;
    double worst = 0.0;
    for (const TerrainDraw& d : list.terrain) {
        if (d.firstVertexIrradiance < 0) continue;
        ++roadDraws;
        const std::vector<glm::vec3> pos = readBack<glm::vec3>(d.mesh->positions);
        const std::vector<glm::vec3> nrm = readBack<glm::vec3>(d.mesh->normals);
        ASSERT_EQ(pos.size(), nrm.size());
        ASSERT_LE(std::size_t(d.firstVertexIrradiance) + pos.size(), list.vertexIrradiance.size());
        glm::dvec3 lo(1e300), hi(-1e300);
        std::vector<glm::dvec3> at(pos.size());
        bool hasTarget = false;
        for (std::size_t v = 0; v < pos.size(); ++v) {
            at[v] = eye + glm::dvec3(d.origin) + glm::dvec3(pos[v]);
            lo = glm::min(lo, at[v]);
            hi = glm::max(hi, at[v]);
            hasTarget = hasTarget || std::hypot(at[v].x - target.x, at[v].z - target.z) < 6.0;
            const glm::vec3 got = list.vertexIrradiance[std::size_t(d.firstVertexIrradiance) + v];
            const glm::vec3 expected = CurvedAmbient::field(at[v], glm::dvec3(nrm[v]));
            worst = std::max(worst, double(glm::length(got - expected)));
        }
        if (!hasTarget) continue;
        ++targetChunks;
        // The old lighting of this chunk, and how far the colours range along it.
        const glm::dvec3 up(0.0, 1.0, 0.0);
        const glm::vec3 e00 = CurvedAmbient::field({lo.x, lo.y, lo.z}, up);
        const glm::vec3 e10 = CurvedAmbient::field({hi.x, lo.y, lo.z}, up);
        const glm::vec3 e01 = CurvedAmbient::field({lo.x, lo.y, hi.z}, up);
        const glm::vec3 e11 = CurvedAmbient::field({hi.x, lo.y, hi.z}, up);
        double fromOld = 0.0, tilt = 0.0;
        glm::vec3 least(1e30f), most(-1e30f);
        for (std::size_t v = 0; v < pos.size(); ++v) {
            const float u = float((at[v].x - lo.x) / std::max(hi.x - lo.x, 1.0));
            const float w = float((at[v].z - lo.z) / std::max(hi.z - lo.z, 1.0));
            const glm::vec3 old = glm::mix(glm::mix(e00, e10, u), glm::mix(e01, e11, u), w);
            const glm::vec3 got = list.vertexIrradiance[std::size_t(d.firstVertexIrradiance) + v];
            fromOld = std::max(fromOld, double(glm::length(got - old)));
            least = glm::min(least, got);
            most = glm::max(most, got);
            tilt = std::max(tilt, std::sqrt(1.0 - double(nrm[v].y) * nrm[v].y));
        }
        EXPECT_GT(tilt, 0.03) << "the stretch is on a grade";
        EXPECT_GT(fromOld, 0.05);
        // 48 segments of 3 m: the field's x and z terms turn by more than a radian along it.
        EXPECT_GT(std::max(most.x - least.x, most.y - least.y), 0.1f);
    }
    EXPECT_GT(roadDraws, 0);
    EXPECT_GE(targetChunks, 1);
    // Positions read back relative to the eye in float: a few micrometres.
    EXPECT_LT(worst, 1e-4);
}

// An ambient that varies within a patch (a few metres across), turns with the normal, and asks
// for patches nearer the eye than range_m to be lit per vertex, at most `budget` new vertices a
// frame (0: no bound); it remembers the sizes the batches asked it to average over.
class VertexFieldAmbient final : public AmbientSource {
  public:
    explicit VertexFieldAmbient(double range_m, int budget = 0)
        : range_m_(range_m), budget_(budget) {}
    static glm::vec3 field(const glm::dvec3& p, const glm::dvec3& n) {
        return glm::vec3(float(1.0 + 0.5 * std::sin(p.x / 3.0)),
                         float(1.0 + 0.5 * std::cos(p.z / 4.0)), float(1.0 + 0.5 * (n.x + n.z)));
    }
    glm::vec3 cornerIrradiance(const glm::dvec3& p, const glm::dvec3& n) const override {
        return field(p, n);
    }
    void cornerIrradianceBatch(std::size_t count, const glm::dvec3* p, const glm::dvec3* n,
                               glm::vec3* out, const double* patch_m = nullptr) const override {
        for (std::size_t i = 0; i < count; ++i) {
            out[i] = field(p[i], n[i]);
            if (patch_m) patches.push_back(patch_m[i]);
            else ++asPoints;
        }
    }
    std::uint32_t objectSet(const glm::dvec3&, std::vector<AmbientSet>& sets) const override {
        sets.emplace_back();
        return std::uint32_t(sets.size() - 1);
    }
    double terrainVertexRange_m() const override { return range_m_; }
    int terrainVertexPointsPerFrame() const override { return budget_; }
    mutable std::vector<double> patches;
    mutable std::size_t asPoints = 0;  // asked without a size to average over

  private:
    double range_m_;
    int budget_;
};

// nearField.vertexAmbient_m (the ambient's terrainVertexRange_m): looking down over open ground,
// the patches nearer the eye than the range take the ambient at their own vertices. Their
// pixels' applied ambient follows a field that varies over metres (within 0.06 of it at the
// pixel, where the corner blend of a 32 m patch misses it by far more), stays surface kind 1
// (terrain, not road) pixel for pixel, and the far terrain is drawn exactly as before; each
// vertex's value is the field at its own position and normal, asked as a point (no size to
// average over, as road vertices are). With the range 0 nothing is lit per vertex
// and the frame is the same, byte for byte, as the one drawn by an ambient without the setting.
TEST(Renderer, NearTerrainIsLitPerVertexWithinTheRange) {
    AMB_REQUIRE_PLATFORM(platform, Backend::Auto, kW, kH);
    const World world(WorldSettings{});
    Renderer renderer(world, testSettings());
    renderer.setTimeOfDay(12.0);
    const CameraSample cam = viewAt(world, -0.35);
    const VertexFieldAmbient off(0.0), on(40.0);
    renderer.render(cam, off, RenderOutput::AmbientIrradiance);
    const SurfaceImage offAov = renderer.readSurface(cam);
    renderer.render(cam, on, RenderOutput::AmbientIrradiance);
    const SurfaceImage onAov = renderer.readSurface(cam);
    renderer.render(cam, on, RenderOutput::Normal);
    const SurfaceImage normals = renderer.readSurface(cam);
    int near = 0, far = 0, nearDiffers = 0;
    double onMiss = 0.0, offMiss = 0.0;
    for (std::size_t p = 0; p < std::size_t(kW) * kH; ++p) {
        const float kind = onAov.rgba[4 * p + 3];
        ASSERT_EQ(kind, offAov.rgba[4 * p + 3]) << "pixel " << p;
        if (kind != 1.0f) continue;
        const glm::dvec3 at = cam.position_m + glm::dvec3(onAov.position[p]);
        const double d = std::hypot(at.x - cam.position_m.x, at.z - cam.position_m.z);
        const glm::vec3 got(onAov.rgba[4 * p], onAov.rgba[4 * p + 1], onAov.rgba[4 * p + 2]);
        const glm::vec3 old(offAov.rgba[4 * p], offAov.rgba[4 * p + 1], offAov.rgba[4 * p + 2]);
        if (d < 25.0) {
            ++near;
            const glm::dvec3 n(normals.rgba[4 * p], normals.rgba[4 * p + 1],
                               normals.rgba[4 * p + 2]);
            const glm::vec3 want = VertexFieldAmbient::field(at, n);
            const double miss = glm::length(got - want), oldMiss = glm::length(old - want);
            EXPECT_LT(miss, 0.06) << "at " << d << " m";
            onMiss += miss, offMiss += oldMiss;
            nearDiffers += glm::length(got - old) > 0.05f;
        } else if (d > 300.0) {
            ++far;
            EXPECT_EQ(got, old) << "at " << d << " m";
        }
    }
    ASSERT_GT(near, 500);
    EXPECT_GT(far, 50);
    EXPECT_GT(offMiss / near, 0.1);
    EXPECT_LT(onMiss, offMiss / 4.0);
    EXPECT_GT(nearDiffers, near / 2);

    // The draw list: the per-vertex patches read the field at their vertices, the roads' and the
    // other patches' draws are as before.
    RendererScene scene(world);
    const glm::vec3 forward(cam.forward), up(cam.up);
    const glm::mat4 viewProj = reversedInfinitePerspective(1.0471976f, float(kW) / kH, 0.1f) *
                               glm::lookAt(glm::vec3(0.0f), forward, up);
    for (const VertexFieldAmbient* ambient : {&off, &on}) {
        DrawList list;
        ambient->patches.clear();
        ambient->asPoints = 0;
        scene.buildView(cam.position_m, viewProj, *ambient, list);
        std::size_t roadVertices = 0;
        int perVertex = 0;
        double worst = 0.0;
        for (const TerrainDraw& d : list.terrain) {
            if (d.road) {
                EXPECT_GE(d.firstVertexIrradiance, 0);
                roadVertices += readBack<glm::vec3>(d.mesh->positions).size();
                continue;
            }
            if (d.firstVertexIrradiance < 0) continue;
            ++perVertex;
            EXPECT_FALSE(d.skyDetail);
            const std::vector<glm::vec3> pos = readBack<glm::vec3>(d.mesh->positions);
            const std::vector<glm::vec3> nrm = readBack<glm::vec3>(d.mesh->normals);
            const std::vector<std::uint32_t> index = readBack<std::uint32_t>(d.mesh->indices);
            for (std::uint32_t i = d.firstIndex; i < d.firstIndex + d.indexCount; ++i) {
                const std::uint32_t v = index[i];
                ASSERT_LT(std::size_t(d.firstVertexIrradiance) + v, list.vertexIrradiance.size());
                const glm::dvec3 at = cam.position_m + glm::dvec3(d.origin) + glm::dvec3(pos[v]);
                const glm::vec3 got =
                    list.vertexIrradiance[std::size_t(d.firstVertexIrradiance) + v];
                worst = std::max(
                    worst,
                    double(glm::length(got - VertexFieldAmbient::field(at, glm::dvec3(nrm[v])))));
            }
        }
        if (ambient == &off) {
            EXPECT_EQ(perVertex, 0);
            EXPECT_EQ(list.vertexIrradiance.size(), roadVertices);
        } else {
            EXPECT_GT(perVertex, 2);
            EXPECT_LT(worst, 1e-4);  // positions read back relative to the eye in float
            // Every vertex asked as a point, none with the 2 m vertex spacing to average over.
            EXPECT_GE(ambient->asPoints, roadVertices + std::size_t(perVertex) * 17 * 17);
            EXPECT_EQ(std::count(ambient->patches.begin(), ambient->patches.end(), 2.0), 0);
        }
    }

    // The range 0 draws what an ambient that knows nothing of it draws, byte for byte.
    class Plain final : public AmbientSource {
      public:
        glm::vec3 cornerIrradiance(const glm::dvec3& p, const glm::dvec3& n) const override {
            return VertexFieldAmbient::field(p, n);
        }
        std::uint32_t objectSet(const glm::dvec3&, std::vector<AmbientSet>& sets) const override {
            sets.emplace_back();
            return std::uint32_t(sets.size() - 1);
        }
    } plain;
    renderer.render(cam, plain, RenderOutput::Shaded);
    const std::vector<unsigned char> plainFrame = renderer.readRgb8();
    const std::vector<float> plainHdr = renderer.readHdr();
    renderer.render(cam, off, RenderOutput::Shaded);
    EXPECT_EQ(renderer.readRgb8(), plainFrame);
    EXPECT_EQ(renderer.readHdr(), plainHdr);
    renderer.render(cam, on, RenderOutput::Shaded);
    EXPECT_NE(renderer.readHdr(), plainHdr);
}

// Whether pixel p of an albedo output is an object's bark (world/Vegetation.cpp kBark).
bool isBark(const SurfaceImage& albedo, std::size_t p, float kind) {
    const glm::vec3 a(albedo.rgba[4 * p], albedo.rgba[4 * p + 1], albedo.rgba[4 * p + 2]);
    return (kind == 3.0f || kind == 4.0f) && glm::length(a - glm::vec3(0.20f, 0.13f, 0.08f)) < 2e-3f;
}

// Checks an object pixel's ambient irradiance `got` against the ambient's SH irradiance at its
// normal, `want` (2e-3 relative): the leaves take all of it, a trunk what its crown leaves of it
// (world/WorldMesh.h occlusion), one share in [0, 1] for every channel. Returns the share.
double expectObjectAmbient(const glm::vec3& got, const glm::vec3& want, bool bark) {
    double share = 1.0;
    if (bark) {
        share = got.g / want.g;
        EXPECT_LE(share, 1.0 + 2e-3);
        EXPECT_GE(share, 0.0);
    }
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], share * want[c], 2e-3 * want[c] + 1e-5);
    return share;
}

// nearField.vertexPointsPerFrame (the ambient's terrainVertexPointsPerFrame): with the eye
// still, the patches in range are lit per vertex a few a frame, never more new vertices than the
// bound (or one patch, when a patch alone is larger), nearest first; the others blend their
// corners meanwhile. Once every one has had its turn the draw list is the unbounded one's, value
// for value; a patch lit stays lit, and the bound of one vertex lights one patch a frame.
TEST(Renderer, PatchesEnteringTheVertexRangeTakeTurnsWithinTheBound) {
    AMB_REQUIRE_PLATFORM(platform, Backend::Auto, kW, kH);
    const World world(WorldSettings{});
    const CameraSample cam = viewAt(world, -0.35);
    const glm::vec3 forward(cam.forward), up(cam.up);
    const glm::mat4 viewProj = reversedInfinitePerspective(1.0471976f, float(kW) / kH, 0.1f) *
                               glm::lookAt(glm::vec3(0.0f), forward, up);
    // The per-vertex patches' first vertex and their values, in draw order.
    const auto litPatches = [](const DrawList& list) {
        std::vector<std::pair<std::uint32_t, std::vector<glm::vec3>>> lit;
        for (const TerrainDraw& d : list.terrain) {
            if (d.road || d.firstVertexIrradiance < 0) continue;
            const std::vector<std::uint32_t> index = readBack<std::uint32_t>(d.mesh->indices);
            std::vector<glm::vec3> values;
            for (std::uint32_t i = d.firstIndex; i < d.firstIndex + d.indexCount; ++i)
                values.push_back(
                    list.vertexIrradiance[std::size_t(d.firstVertexIrradiance) + index[i]]);
            lit.emplace_back(index[d.firstIndex], values);
        }
        return lit;
    };
    const VertexFieldAmbient unbounded(80.0);
    RendererScene all(world);
    DrawList want;
    SceneStats wantStats;
    all.buildView(cam.position_m, viewProj, unbounded, want, &wantStats);
    ASSERT_GE(wantStats.terrainPatchesVertex, 6u);
    EXPECT_EQ(wantStats.terrainPatchesWaiting, 0u);
    constexpr std::size_t kPatchVertices = 17 * 17;
    for (int budget : {int(2 * kPatchVertices), 1}) {
        const VertexFieldAmbient bounded(80.0, budget);
        RendererScene scene(world);
        std::size_t lit = 0;
        int frames = 0;
        DrawList list;
        SceneStats stats;
        do {
            list.clear();
            scene.buildView(cam.position_m, viewProj, bounded, list, &stats);
            ++frames;
            ASSERT_GE(stats.terrainPatchesVertex, lit + 1) << "frame " << frames;
            ASSERT_LE(stats.terrainPatchesVertex, lit + std::max<std::size_t>(
                                                            1, std::size_t(budget) / kPatchVertices))
                << "frame " << frames;
            EXPECT_EQ(stats.terrainPatchesVertex + stats.terrainPatchesWaiting,
                      wantStats.terrainPatchesVertex);
            // Nearest first: in the draw list (nearest first), no patch in range waits before
            // one lit per vertex.
            bool waitingSeen = false;
            for (const TerrainDraw& d : list.terrain) {
                if (d.road) continue;
                const double x0 = double(d.origin.x) + d.rect.x, z0 = double(d.origin.z) + d.rect.y;
                const double size = 1.0 / d.rect.z;
                const double dx = std::max({x0, 0.0, -x0 - size});
                const double dz = std::max({z0, 0.0, -z0 - size});
                const bool perVertex = d.firstVertexIrradiance >= 0;
                if (perVertex) EXPECT_FALSE(waitingSeen) << "frame " << frames;
                if (!perVertex && std::hypot(dx, dz) < 79.9) waitingSeen = true;
            }
            lit = stats.terrainPatchesVertex;
        } while (stats.terrainPatchesWaiting > 0 && frames < 100);
        EXPECT_EQ(stats.terrainPatchesWaiting, 0u) << budget;
        EXPECT_GE(frames, budget == 1 ? int(wantStats.terrainPatchesVertex) : 3) << budget;
        const auto got = litPatches(list), expected = litPatches(want);
        ASSERT_EQ(got.size(), expected.size()) << budget;
        for (std::size_t k = 0; k < got.size(); ++k) {
            EXPECT_EQ(got[k].first, expected[k].first) << budget;
            EXPECT_EQ(got[k].second, expected[k].second) << budget;
        }
        // Lit patches stay lit.
        list.clear();
        scene.buildView(cam.position_m, viewProj, bounded, list, &stats);
        EXPECT_EQ(stats.terrainPatchesVertex, wantStats.terrainPatchesVertex);
    }
}

// The screen witnesses' outputs: with the constant ambient (E(n) = pi x mean radiance for every
// normal) the ambient-irradiance output is that constant at every surface pixel, for terrain and
// plants alike; the normal output is unit length and faces the camera; the positions read back
// from depth lie on the terrain under terrain pixels (within 0.5 m), and the sky is alpha 0.
// A trunk's pixel takes the share of that constant its crown leaves.
TEST(Renderer, ScreenWitnessOutputsAreWhatTheDrawApplies) {
    AMB_REQUIRE_PLATFORM(platform, Backend::Auto, kW, kH);
    const World world(WorldSettings{});
    Renderer renderer(world, testSettings());
    const FixedAmbient ambient(AmbientMode::Constant, renderer.setTimeOfDay(10.0));
    const glm::vec3 expected = shIrradiance(ambient.sh(), glm::vec3(0.0f, 1.0f, 0.0f));
    const CameraSample cam = viewAt(world, -0.05);
    renderer.render(cam, ambient, RenderOutput::AmbientIrradiance);
    const SurfaceImage applied = renderer.readSurface(cam);
    renderer.render(cam, ambient, RenderOutput::Normal);
    const SurfaceImage normals = renderer.readSurface(cam);
    renderer.render(cam, ambient, RenderOutput::Albedo);
    const SurfaceImage albedo = renderer.readSurface(cam);
    ASSERT_EQ(applied.rgba.size(), std::size_t(kW) * kH * 4);
    int surface = 0, sky0 = 0, onTerrain = 0, terrain = 0;
    for (std::size_t p = 0; p < std::size_t(kW) * kH; ++p) {
        const float kind = applied.rgba[4 * p + 3];
        if (kind == 0.0f) {
            ++sky0;
            continue;
        }
        ++surface;
        // A trunk takes what its crown leaves of the ambient (world/WorldMesh.h occlusion).
        const double share = isBark(albedo, p, kind) ? applied.rgba[4 * p + 1] / expected[1] : 1.0;
        EXPECT_LE(share, 1.0 + 1e-3);
        EXPECT_GE(share, 0.0);
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(applied.rgba[4 * p + c], share * expected[c], 1e-3 * expected[c] + 1e-6);
        const glm::vec3 n(normals.rgba[4 * p], normals.rgba[4 * p + 1], normals.rgba[4 * p + 2]);
        EXPECT_NEAR(glm::length(n), 1.0f, 1e-3f);
        EXPECT_EQ(normals.rgba[4 * p + 3], kind);
        if (kind == 1.0f) {
            ++terrain;
            const glm::dvec3 w = cam.position_m + glm::dvec3(applied.position[p]);
            onTerrain += std::abs(w.y - world.height(w.x, w.z)) < 0.5;
        }
    }
    EXPECT_GT(surface, kW * kH / 4);
    EXPECT_GT(sky0, 0);
    ASSERT_GT(terrain, 100);
    EXPECT_GT(onTerrain, terrain * 9 / 10);
}

// A camera 14 m south of the tree nearest an open spot (eastwards until one is near), 2 m above
// the ground, looking at the tree 1 m above its base.
CameraSample treeView(const World& world) {
    glm::dvec3 ground = test::openGround(world);
    std::vector<Plant> near;
    for (int step = 0; step < 40 && near.empty(); ++step) {
        ground.x += 400.0;  // eastwards until a tree is near
        near = world.vegetation().inDisc(ground.x, ground.z, 200.0);
        near.erase(std::remove_if(near.begin(), near.end(),
                                  [](const Plant& p) {
                                      return p.kind != PlantKind::Conifer &&
                                             p.kind != PlantKind::Broadleaf;
                                  }),
                   near.end());
    }
    EXPECT_FALSE(near.empty());
    if (near.empty()) return viewAt(world, 0.0);
    const Plant& plant = *std::min_element(near.begin(), near.end(), [&](const Plant& a, const Plant& b) {
        return std::hypot(a.position_m.x - ground.x, a.position_m.z - ground.z) <
               std::hypot(b.position_m.x - ground.x, b.position_m.z - ground.z);
    });
    CameraSample cam;
    cam.position_m = plant.position_m + glm::dvec3(0.0, 0.0, 14.0);
    cam.position_m.y = world.height(cam.position_m.x, cam.position_m.z) + 2.0;
    cam.forward = glm::normalize(plant.position_m + glm::dvec3(0.0, 1.0, 0.0) - cam.position_m);
    cam.up = glm::normalize(glm::cross(glm::cross(cam.forward, glm::dvec3(0, 1, 0)), cam.forward));
    return cam;
}

// The ambient view (--view ambient): every surface pixel is a white Lambertian surface lit by
// the ambient alone, radiance = E / pi. With the hemisphere ambient (E varies with the normal)
// an object pixel equals the SH irradiance at its normal (read from the normal output) over pi,
// within 2e-3 relative (a trunk's pixel: the share of it its crown leaves, one share for all
// channels, darker than 0.95 somewhere on the trunk the view looks at); every surface pixel equals the screen witnesses' ambient output over pi
// (the same corner and vertex colours) within 1.5e-3 (the HDR target is half float: 2^-11 a
// rounding, two roundings); the sky stays the shaded view's. The tree view shows no sky: a pixel
// its surface output calls sky is a surface read back before it was drawn (the read-back right
// after the two tone-mapped views did that until it waited for the rasterizer: app/render/Gl.h,
// readFramebuffer), and the views differ there. A second view, looking up from open ground, has
// sky in its top rows: there the ambient view is the shaded view, value for value.
TEST(Renderer, TheAmbientViewIsTheShIrradianceOverPi) {
    AMB_REQUIRE_PLATFORM(platform, Backend::Auto, kW, kH);
    const World world(WorldSettings{});
    Renderer renderer(world, testSettings());
    const FixedAmbient ambient(AmbientMode::Hemisphere, renderer.setTimeOfDay(10.0));
    // Looking at a tree from 14 m, so objects fill part of the view.
    const CameraSample cam = treeView(world);
    renderer.render(cam, ambient, RenderOutput::Ambient);
    const std::vector<float> view = renderer.readHdr();
    renderer.render(cam, ambient, RenderOutput::Shaded);
    const std::vector<float> shaded = renderer.readHdr();
    renderer.render(cam, ambient, RenderOutput::AmbientIrradiance);
    const SurfaceImage applied = renderer.readSurface(cam);
    renderer.render(cam, ambient, RenderOutput::Normal);
    const SurfaceImage normals = renderer.readSurface(cam);
    renderer.render(cam, ambient, RenderOutput::Albedo);
    const SurfaceImage albedo = renderer.readSurface(cam);
    ASSERT_EQ(view.size(), std::size_t(kW) * kH * 3);
    int objects = 0, surface = 0, sky0 = 0, trunk = 0, shadedTrunk = 0;
    float spread = 0.0f, least = 1e30f;
    for (std::size_t p = 0; p < std::size_t(kW) * kH; ++p) {
        const float kind = applied.rgba[4 * p + 3];
        const glm::vec3 got(view[3 * p], view[3 * p + 1], view[3 * p + 2]);
        if (kind == 0.0f) {
            ++sky0;
            for (int c = 0; c < 3; ++c) EXPECT_EQ(got[c], shaded[3 * p + c]);
            continue;
        }
        ++surface;
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(got[c] * kPi, applied.rgba[4 * p + c], 1.5e-3 * applied.rgba[4 * p + c] + 1e-6);
        if (kind == 3.0f || kind == 4.0f) {
            ++objects;
            const glm::vec3 n(normals.rgba[4 * p], normals.rgba[4 * p + 1], normals.rgba[4 * p + 2]);
            const glm::vec3 want = glm::max(shIrradiance(ambient.sh(), glm::normalize(n)), glm::vec3(0.0f));
            const bool bark = isBark(albedo, p, kind);
            const double share = expectObjectAmbient(got * float(kPi), want, bark);
            trunk += bark, shadedTrunk += bark && share < 0.95;
            spread = std::max(spread, got.g), least = std::min(least, got.g);
        }
    }
    EXPECT_GT(trunk, 0);  // the view looks at the trunk, 1 m above its base
    EXPECT_GT(shadedTrunk, 0);
    EXPECT_GT(surface, kW * kH / 4);
    ASSERT_GT(objects, 50);
    ::testing::Test::RecordProperty("skyPixels", sky0);
    // The hemisphere ambient varies with the normal: the test sees more than one value.
    EXPECT_GT(spread, 1.2f * least);

    const CameraSample up = viewAt(world, 0.2);
    renderer.render(up, ambient, RenderOutput::Ambient);
    const std::vector<float> upView = renderer.readHdr();
    renderer.render(up, ambient, RenderOutput::Shaded);
    const std::vector<float> upShaded = renderer.readHdr();
    renderer.render(up, ambient, RenderOutput::AmbientIrradiance);
    const SurfaceImage upApplied = renderer.readSurface(up);
    int sky = 0, skyDiffers = 0;
    for (std::size_t p = 0; p < std::size_t(kW) * kH; ++p) {
        if (upApplied.rgba[4 * p + 3] != 0.0f) continue;
        ++sky;
        for (int c = 0; c < 3; ++c) skyDiffers += upView[3 * p + c] != upShaded[3 * p + c];
    }
    EXPECT_GT(sky, kW * kH / 8);
    EXPECT_EQ(skyDiffers, 0);
}

// A read-back is the image its render drew, whole: right after two tone-mapped renders of the
// same camera, the screen witnesses' render read back at once equals the same target read again
// after glFinish, pixel for pixel, and so do the HDR and tone-mapped images of a shaded render
// after it. Without the wait in readFramebuffer (app/render/Gl.h) llvmpipe returned tiles of
// the surface output its rasterizer threads had not yet drawn (alpha 0: terrain read as sky).
TEST(Renderer, ReadBacksWaitForTheRenderTheyRead) {
    AMB_REQUIRE_PLATFORM(platform, Backend::Auto, kW, kH);
    const World world(WorldSettings{});
    Renderer renderer(world, testSettings());
    const FixedAmbient ambient(AmbientMode::Hemisphere, renderer.setTimeOfDay(10.0));
    const CameraSample cam = treeView(world);
    // Values that differ, and any the longer vector has beyond the shorter.
    const auto differing = [](const auto& a, const auto& b) {
        const std::size_t n = std::min(a.size(), b.size());
        int count = int(std::max(a.size(), b.size()) - n);
        for (std::size_t i = 0; i < n; ++i) count += !(a[i] == b[i]);
        return count;
    };
    // The sequence of TheAmbientViewIsTheShIrradianceOverPi.
    renderer.render(cam, ambient, RenderOutput::Ambient);
    (void)renderer.readHdr();
    renderer.render(cam, ambient, RenderOutput::Shaded);
    (void)renderer.readHdr();
    renderer.render(cam, ambient, RenderOutput::AmbientIrradiance);
    const SurfaceImage first = renderer.readSurface(cam);
    glFinish();
    EXPECT_EQ(differing(first.rgba, renderer.readSurface(cam).rgba), 0) << "surface output";
    renderer.render(cam, ambient, RenderOutput::Shaded);
    const std::vector<float> hdr = renderer.readHdr();
    const std::vector<unsigned char> ldr = renderer.readRgb8();
    glFinish();
    EXPECT_EQ(differing(hdr, renderer.readHdr()), 0) << "HDR image";
    EXPECT_EQ(differing(ldr, renderer.readRgb8()), 0) << "tone-mapped image";
}

// The ambient view is not shadowed: it shows the ambient alone, and the ambient is what lights
// a surface in shadow. Looking at a tree at 10 h with the hemisphere ambient, pixels in shadow
// (shaded luminance with shadows below 0.7 x without) exist on terrain and on the tree; there
// the ambient view with shadows is the same image as without (to 1e-6 relative), an object
// pixel equals the SH irradiance at its normal over pi (lighting/SH.h, 2e-3 relative, a trunk's
// the share of it its crown leaves, as above)
// and a terrain pixel the applied corner colours over pi (1.5e-3: two half-float roundings).
TEST(Renderer, TheAmbientViewIsNotShadowed) {
    AMB_REQUIRE_PLATFORM(platform, Backend::Auto, kW, kH);
    const World world(WorldSettings{});
    RenderSettings off = testSettings();
    off.shadows.enabled = false;
    Renderer lit(world, off), shadowed(world, testSettings());
    ASSERT_NE(shadowed.shadowMap(), nullptr);
    EXPECT_EQ(lit.shadowMap(), nullptr);
    const FixedAmbient ambient(AmbientMode::Hemisphere, shadowed.setTimeOfDay(10.0));
    lit.setTimeOfDay(10.0);
    const CameraSample cam = treeView(world);
    const auto image = [&](Renderer& r, RenderOutput out) {
        r.render(cam, ambient, out);
        return r.readHdr();
    };
    const std::vector<float> shadedOn = image(shadowed, RenderOutput::Shaded);
    const std::vector<float> shadedOff = image(lit, RenderOutput::Shaded);
    const std::vector<float> viewOn = image(shadowed, RenderOutput::Ambient);
    const std::vector<float> viewOff = image(lit, RenderOutput::Ambient);
    shadowed.render(cam, ambient, RenderOutput::AmbientIrradiance);
    const SurfaceImage applied = shadowed.readSurface(cam);
    shadowed.render(cam, ambient, RenderOutput::Normal);
    const SurfaceImage normals = shadowed.readSurface(cam);
    shadowed.render(cam, ambient, RenderOutput::Albedo);
    const SurfaceImage albedo = shadowed.readSurface(cam);
    int inShadow = 0, objectsInShadow = 0, terrainInShadow = 0;
    for (std::size_t p = 0; p < std::size_t(kW) * kH; ++p) {
        for (int c = 0; c < 3; ++c)
            ASSERT_NEAR(viewOn[3 * p + c], viewOff[3 * p + c], 1e-6f * viewOff[3 * p + c] + 1e-9f);
        const float kind = applied.rgba[4 * p + 3];
        if (kind == 0.0f) continue;
        const auto lum = [&](const std::vector<float>& v) {
            return luminance(glm::vec3(v[3 * p], v[3 * p + 1], v[3 * p + 2]));
        };
        if (!(lum(shadedOn) < 0.7f * lum(shadedOff))) continue;
        ++inShadow;
        const glm::vec3 got(viewOn[3 * p], viewOn[3 * p + 1], viewOn[3 * p + 2]);
        if (kind == 3.0f || kind == 4.0f) {
            ++objectsInShadow;
            const glm::vec3 n(normals.rgba[4 * p], normals.rgba[4 * p + 1], normals.rgba[4 * p + 2]);
            const glm::vec3 want =
                glm::max(shIrradiance(ambient.sh(), glm::normalize(n)), glm::vec3(0.0f));
            expectObjectAmbient(got * float(kPi), want, isBark(albedo, p, kind));
        } else {
            terrainInShadow += kind == 1.0f;
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(got[c] * kPi, applied.rgba[4 * p + c],
                            1.5e-3 * applied.rgba[4 * p + c] + 1e-6);
        }
    }
    ::testing::Test::RecordProperty("pixelsInShadow", inShadow);
    EXPECT_GT(objectsInShadow, 20);
    EXPECT_GT(terrainInShadow, 20);
}


// Pass timing (--pass-timing, app/render/PassTimer.h) waits between the passes and counts
// them; it changes no pixel. Over the highway, behind a car, at 10 h: two frames each with
// timing on and off give the same tone-mapped and HDR images, byte for byte; with timing every
// pass of the frame is counted: the cascades (first frame), the car's map, plants, car, roads,
// terrain, sky, the exposure meter and the tone mapping, each geometry pass with triangles and
// samples, and the samples of the surfaces and the sky cover the image (overdraw only adds).
TEST(Renderer, PassTimingCountsEveryPassAndChangesNoPixel) {
    AMB_REQUIRE_PLATFORM(platform, Backend::Auto, kW, kH);
    const World world(WorldSettings{});
    const Road& road = world.roads().roads().front();
    const std::size_t i = road.centreline.size() / 3;
    const glm::dvec3 at = road.centreline[i];
    glm::dvec3 along = road.centreline[i + 4] - at;
    along.y = 0.0;
    along = glm::normalize(along);
    CameraSample cam;
    cam.position_m = at - 7.0 * along + glm::dvec3(0.0, 3.0, 0.0);
    cam.forward = glm::normalize(along + glm::dvec3(0.0, -0.2, 0.0));
    cam.up = glm::normalize(glm::cross(glm::cross(cam.forward, glm::dvec3(0, 1, 0)), cam.forward));
    ViewState state;
    state.vehicle = VehiclePose{at, std::atan2(along.x, along.z), 0.0};
    struct Run {
        std::vector<unsigned char> ldr;
        std::vector<float> hdr;
        std::vector<RenderStats> stats;
    };
    const auto run = [&](bool timed) {
        RenderSettings rs = testSettings();
        rs.passTiming = timed;
        Renderer r(world, rs);
        const FixedAmbient ambient(AmbientMode::Hemisphere, r.setTimeOfDay(10.0));
        Run out;
        for (int frame = 0; frame < 2; ++frame) {
            state.time_s = frame / 30.0;
            r.setViewState(state);
            out.stats.push_back(r.drawView(cam, ambient));
        }
        out.ldr = r.readRgb8();
        out.hdr = r.readHdr();
        return out;
    };
    const Run plain = run(false), timed = run(true);
    EXPECT_EQ(plain.ldr, timed.ldr) << "tone-mapped image";
    EXPECT_EQ(plain.hdr, timed.hdr) << "HDR image";
    EXPECT_FALSE(plain.stats[0].passesTimed);
    ASSERT_TRUE(timed.stats[0].passesTimed);
    const auto& first = timed.stats[0].passes;
    const auto pass = [&](RenderPass p) { return first[std::size_t(int(p))]; };
    for (RenderPass p : {RenderPass::ShadowCascades, RenderPass::ShadowCar, RenderPass::Plants,
                         RenderPass::Car, RenderPass::Roads, RenderPass::Terrain, RenderPass::Sky,
                         RenderPass::Exposure, RenderPass::Tonemap}) {
        EXPECT_TRUE(pass(p).ran) << toString(p);
        EXPECT_GE(pass(p).ms, 0.0) << toString(p);
        if (p != RenderPass::Exposure) {
            EXPECT_GT(pass(p).triangles, 0u) << toString(p);
        }
    }
    for (RenderPass p : {RenderPass::ShadowCascades, RenderPass::Plants, RenderPass::Car,
                         RenderPass::Roads, RenderPass::Terrain, RenderPass::Sky})
        EXPECT_GT(pass(p).samples, 0u) << toString(p);
    std::uint64_t covered = 0;
    for (RenderPass p : {RenderPass::Plants, RenderPass::Car, RenderPass::Roads,
                         RenderPass::Terrain, RenderPass::Sky})
        covered += pass(p).samples;
    EXPECT_GE(covered, std::uint64_t(kW) * kH);
    // The draw's triangles are the passes' (plants, car, roads, terrain).
    std::size_t drawn = 0;
    for (RenderPass p : {RenderPass::Plants, RenderPass::Car, RenderPass::Roads, RenderPass::Terrain})
        drawn += pass(p).triangles;
    EXPECT_EQ(drawn, timed.stats[0].triangles);
    EXPECT_EQ(pass(RenderPass::Tonemap).samples, std::uint64_t(kW) * kH);
}

}  // namespace
}  // namespace amb

namespace amb {
namespace {
// Night frames read: the day time-lapse's view (replays/day-timelapse.json: its world and
// camera) at 21:50, lit by the moon (the main light at night, world/Sky.h) and the night sky,
// tone mapped with the exposure metered on the frame, has a mean display luminance (Rec. 709
// weights on the 8-bit values) of at least 20 of 255, and stays below the same view at dusk
// (20:00) and at noon: the night is readable but darker than the day.
TEST(Renderer, NightFramesReadAndStayDarkerThanDusk) {
    AMB_REQUIRE_PLATFORM(platform, Backend::Auto, kW, kH);
    const World world(WorldSettings{});
    CameraSample cam;
    cam.position_m = glm::dvec3(-4200.0, 11.279953818851169, -5000.0);
    cam.forward = glm::dvec3(0.8627299156628211, 0.08715574274765818, 0.4980973490458726);
    cam.up = glm::dvec3(-0.07547908730517336, 0.9961946980917455, -0.043577871373829076);
    const auto meanLuminance = [&](double h, SkyLighting* skyOut) {
        Renderer r(world, testSettings());
        const SkyLighting& sky = r.setTimeOfDay(h);
        if (skyOut) *skyOut = sky;
        const FixedAmbient ambient(AmbientMode::Hemisphere, sky);
        r.render(cam, ambient);
        const std::vector<unsigned char> ldr = r.readRgb8();
        double sum = 0.0;
        for (std::size_t i = 0; i + 2 < ldr.size(); i += 3)
            sum += luminance(glm::vec3(ldr[i], ldr[i + 1], ldr[i + 2]));
        return sum / double(ldr.size() / 3);
    };
    SkyLighting night;
    const double atNight = meanLuminance(21.0 + 50.0 / 60.0, &night);
    const double atDusk = meanLuminance(20.0, nullptr), atNoon = meanLuminance(12.0, nullptr);
    ::testing::Test::RecordProperty("nightMean", std::to_string(atNight));
    ::testing::Test::RecordProperty("duskMean", std::to_string(atDusk));
    EXPECT_GT(night.lightDir.y, 0.0f) << "the moon is up at 21:50";
    EXPECT_GE(atNight, 20.0);
    EXPECT_LT(atNight, atDusk);
    EXPECT_LT(atNight, atNoon);
}
}  // namespace
}  // namespace amb

namespace amb {
namespace {
// The far terrain cascade (ShadowSettings::farDistance_m) shades terrain beyond the cascades:
// at 18 h (the sun about 10 degrees up), 150 m above the most rugged of 49 spots, looking across
// the light 14 degrees down, with the far cascade to 800 m and without. Of the pixels whose
// surface lies within 780 m but outside every cascade's map (across the light, beyond the
// corner of its square), at least 3 % are in shadow with it (luminance below 0.7 x the same
// pixel without it: without it no map covers them, so they are lit). Well inside a cascade
// (within 0.85 of its radius across the light, away from the hand-over band) the two images are
// the same.
TEST(Renderer, TheFarCascadeShadesTerrainBeyondTheCascades) {
    AMB_REQUIRE_PLATFORM(platform, Backend::Auto, kW, kH);
    const World world(WorldSettings{});
    const double h = 18.0;
    RenderSettings nearOnly = testSettings(), withFar = testSettings();
    nearOnly.shadows.farDistance_m = 0.0;
    withFar.shadows.farDistance_m = 800.0;
    Renderer a(world, nearOnly), b(world, withFar);
    const SkyLighting& sky = a.setTimeOfDay(h);
    b.setTimeOfDay(h);
    const FixedAmbient ambient(AmbientMode::Hemisphere, sky);
    CameraSample cam;
    // The most rugged of a few spots: the widest spread of heights 400 m around it.
    double x = 0.0, z = 0.0, best = -1.0;
    for (int i = -3; i <= 3; ++i)
        for (int k = -3; k <= 3; ++k) {
            const double cx = 1500.0 * i, cz = 1500.0 * k;
            double lo = 1e9, hi = -1e9;
            for (int a = 0; a < 16; ++a) {
                const double y = world.height(cx + 400.0 * std::cos(a * 0.3927),
                                              cz + 400.0 * std::sin(a * 0.3927));
                lo = std::min(lo, y), hi = std::max(hi, y);
            }
            if (hi - lo > best) best = hi - lo, x = cx, z = cz;
        }
    cam.position_m = glm::dvec3(x, world.height(x, z) + 150.0, z);
    // Across the light: cast shadows lie beside what casts them.
    const glm::dvec3 sideways = glm::normalize(glm::dvec3(-sky.lightDir.z, 0.0, sky.lightDir.x));
    cam.forward = glm::normalize(sideways + glm::dvec3(0.0, -0.25, 0.0));
    cam.up = glm::normalize(glm::cross(glm::cross(cam.forward, glm::dvec3(0, 1, 0)), cam.forward));
    a.render(cam, ambient, RenderOutput::Albedo);
    const SurfaceImage surface = a.readSurface(cam);
    a.render(cam, ambient);
    b.render(cam, ambient);
    const std::vector<float> off = a.readHdr(), on = b.readHdr();
    int far = 0, farShadowed = 0, nearPixels = 0, nearDiffer = 0;
    // Outside every cascade's map: across the light, further from its centre than the corner of
    // its square (half-side its radius).
    const ShadowMap& maps = *a.shadowMap();
    const glm::dvec3 light = glm::normalize(glm::dvec3(sky.lightDir));
    // A cascade covers what lies across the light within its square (half-side its radius);
    // the last one hands over to the far cascade in its outer tenth.
    const auto across = [&](const glm::vec3& rel, int k) {
        const glm::dvec3 d = cam.position_m + glm::dvec3(rel) - maps.centre(k);
        return glm::length(d - glm::dot(d, light) * light) / maps.radius(k);
    };
    const auto beyondCascades = [&](const glm::vec3& rel) {
        for (int k = 0; k < nearOnly.shadows.cascades; ++k)
            if (across(rel, k) <= 1.415) return false;
        return true;
    };
    const auto wellInside = [&](const glm::vec3& rel) {
        for (int k = 0; k < nearOnly.shadows.cascades; ++k)
            if (across(rel, k) <= 0.85) return true;
        return false;
    };
    for (std::size_t p = 0; p < std::size_t(kW) * kH; ++p) {
        if (!(surface.rgba[4 * p + 3] > 0.0f)) continue;
        const double d = glm::length(surface.position[p]);
        const auto lum = [&](const std::vector<float>& v) {
            return luminance(glm::vec3(v[3 * p], v[3 * p + 1], v[3 * p + 2]));
        };
        if (wellInside(surface.position[p])) {
            ++nearPixels;
            nearDiffer += lum(on) != lum(off);
        } else if (d < 780.0 && beyondCascades(surface.position[p])) {
            ++far;
            farShadowed += lum(on) < 0.7f * lum(off);
        }
    }
    ::testing::Test::RecordProperty("farPixels", far);
    ::testing::Test::RecordProperty("farShadowed", farShadowed);
    ASSERT_GT(far, 500);
    EXPECT_GT(farShadowed, far * 3 / 100);
    EXPECT_GT(nearPixels, 100);
    EXPECT_EQ(nearDiffer, 0);
}
}  // namespace
}  // namespace amb
