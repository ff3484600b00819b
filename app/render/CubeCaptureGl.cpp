// CubeCaptureGl.cpp — render cube faces of the static coarse scene and read them back.
//
// Steps per call: (1) the capture scene around the probe (terrain proxy, tree proxies, roads;
// RendererScene::buildCapture) lit by the sky/ground hemisphere ambient and the main light;
// (2) each requested face into its rows of the N x 6N target; (3) one read-back; (4) the sun
// disc, far smaller than a 16-texel face's texels, added to the texel holding the sun direction
// with its whole energy when that texel sees sky (alpha = 1), so the projection keeps the sun's
// irradiance exactly instead of missing it or hitting it by chance (lighting/SunTexel.h: the
// texel by the one rule every consumer uses, told the direction by sunDirection()).
#include "app/render/CubeCaptureGl.h"

#include <chrono>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "app/frame/MethodStages.h"
#include "app/render/Renderer.h"
#include "lighting/CubeMapProjector.h"
#include "lighting/SunTexel.h"
#include "world/Conventions.h"
#include "world/Error.h"
#include "world/World.h"

namespace amb {

namespace {

struct FaceBasis {
    glm::vec3 forward, u, v;
};

FaceBasis faceBasis(int face) {
    const glm::dvec3 f = cubeFaceDirection(face, 0.0, 0.0);
    return {glm::vec3(f), glm::vec3(cubeFaceDirection(face, 1.0, 0.0) - f),
            glm::vec3(cubeFaceDirection(face, 0.0, 1.0) - f)};
}

constexpr float kCaptureNear_m = 0.1f;

// The objects of `list` whose bounding spheres reach into face f's 90-degree frustum (its four
// side planes through the probe), into `out` (terrain and ambient sets shared by reference:
// copied once, the instances filtered). Exact for what the face shows: a face draws only what
// it can see, about a quarter of the trees around a probe.
void cullObjectsToFace(const DrawList& list, int face, DrawList& out) {
    const FaceBasis b = faceBasis(face);
    const glm::vec3 n[4] = {b.forward - b.u, b.forward + b.u, b.forward - b.v, b.forward + b.v};
    out.objects.resize(list.objects.size());
    for (std::size_t k = 0; k < list.objects.size(); ++k) {
        const ObjectBatch& src = list.objects[k];
        ObjectBatch& dst = out.objects[k];
        dst.mesh = src.mesh;
        dst.simplified = src.simplified;
        dst.instances.clear();
        for (const ObjectInstance& inst : src.instances) {
            const glm::vec3 c(inst.positionScale);
            const float r = src.mesh->boundRadius_m * inst.positionScale.w * 1.4143f;  // |n| = sqrt 2
            if (glm::dot(n[0], c) >= -r && glm::dot(n[1], c) >= -r && glm::dot(n[2], c) >= -r &&
                glm::dot(n[3], c) >= -r)
                dst.instances.push_back(inst);
        }
    }
}

}  // namespace

// The ambient of a surface light (lighting/CubeCapture.h SurfaceLight): its SH at the surface
// point, as the draw applies any ambient (irradiance for the normal, floored at zero; objects
// through R&H's matrices at their ground point).
class FieldAmbient final : public AmbientSource {
  public:
    explicit FieldAmbient(const SurfaceLight* light) : light_(light) {}
    glm::vec3 cornerIrradiance(const glm::dvec3& position_m,
                               const glm::dvec3& normal) const override {
        return glm::max(shIrradiance(light_->shAt(position_m), glm::vec3(normal)),
                        glm::vec3(0.0f));
    }
    std::uint32_t objectSet(const glm::dvec3& position_m,
                            std::vector<AmbientSet>& sets) const override {
        // Plants whose light is the same as the last one's share its set (a light that varies
        // only near the camera gives most of a capture's plants one value).
        const ShRgb sh = light_->shAt(position_m);
        if (&sets == lastSets_ && lastSet_ < sets.size() && sh.c == lastSh_.c) return lastSet_;
        const ShIrradianceMatrices m = shIrradianceMatrices(sh);
        sets.push_back(AmbientSet{m.r, m.g, m.b});
        lastSets_ = &sets, lastSet_ = std::uint32_t(sets.size() - 1), lastSh_ = sh;
        return lastSet_;
    }

  private:
    const SurfaceLight* light_;
    mutable const std::vector<AmbientSet>* lastSets_ = nullptr;
    mutable std::uint32_t lastSet_ = 0;
    mutable ShRgb lastSh_;
};

glm::mat4 CubeCaptureGl::faceViewProj(int face, float near_m) {
    const FaceBasis b = faceBasis(face);
    glm::mat4 view(1.0f);  // rows U, V, -F (glm is column-major: m[col][row])
    for (int c = 0; c < 3; ++c) {
        view[c][0] = b.u[c];
        view[c][1] = b.v[c];
        view[c][2] = -b.forward[c];
    }
    return reversedInfinitePerspective(0.5f * float(kPi), 1.0f, near_m) * view;
}

CubeCaptureGl::CubeCaptureGl(RendererScene& scene, int faceSize, const ShadowSettings& shadows)
    : scene_(&scene), n_(faceSize), shadows_(shadows) {
    init();
}

CaptureScene parseCaptureScene(const std::string& text, const std::string& where) {
    if (text == "coarse") return CaptureScene::Coarse;
    if (text == "full") return CaptureScene::Full;
    throw InputError(where, "expected coarse or full, got '" + text + "'");
}

const char* toString(CaptureScene scene) {
    return scene == CaptureScene::Full ? "full" : "coarse";
}

RendererSceneSettings fullCaptureSceneSettings(int faceSize) {
    RendererSceneSettings s;
    s.pixelsPerRadian = double(faceSize) / (0.5 * kPi);
    s.fullMeshMinPixels = 3.0;
    s.proxyMinPixels = 0.0;
    s.farMinPixels = 0.25;  // leave out plants smaller than a quarter texel
    s.objectsAtCrown = true;
    return s;
}

static std::unique_ptr<RendererScene> ownScene(const World& world, int faceSize,
                                               CaptureScene kind) {
    if (kind == CaptureScene::Full) {
        if (faceSize < 1 || faceSize > 2048)
            throw InputError("--size", "face size must be in [1, 2048]");
        return std::make_unique<RendererScene>(world, fullCaptureSceneSettings(faceSize));
    }
    return std::make_unique<RendererScene>(world);
}

CubeCaptureGl::CubeCaptureGl(const World& world, int faceSize, CaptureScene scene,
                             const ShadowSettings& shadows)
    : ownedScene_(ownScene(world, faceSize, scene)),
      scene_(ownedScene_.get()),
      n_(faceSize),
      kind_(scene),
      shadows_(shadows) {
    init();
}

CubeCaptureGl::~CubeCaptureGl() = default;

void CubeCaptureGl::init() {
    if (n_ < 1 || n_ > 2048) throw InputError("--size", "face size must be in [1, 2048]");
    checkShadowSettings(shadows_, "shadow settings");
    drawer_ = std::make_unique<SceneDrawer>();
    colour_ = makeTexture2D(GL_RGBA32F, n_, 6 * n_);
    depth_ = makeTexture2D(GL_DEPTH_COMPONENT32F, n_, 6 * n_);
    GLuint fbo = 0;
    glCreateFramebuffers(1, &fbo);
    fbo_ = GlFramebuffer(fbo);
    glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT0, colour_.id(), 0);
    glNamedFramebufferTexture(fbo, GL_DEPTH_ATTACHMENT, depth_.id(), 0);
    if (glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
        throw std::runtime_error("capture: incomplete framebuffer");
    }
}

ShadowBinding CubeCaptureGl::prepareShadows(const glm::dvec3& probe_m) {
    ShadowBinding binding;
    const ShadowSettings& ss = shadows_;
    using Clock = std::chrono::steady_clock;
    if (kind_ == CaptureScene::Full) {
        // The main view's cascades around the probe, rendered for this capture's faces.
        if (!ss.enabled) return binding;
        if (!shadowMap_) shadowMap_ = std::make_unique<ShadowMap>(ss.cascades, ss.mapSize);
        const auto t0 = Clock::now();
        shadowStats_.triangles = 0;
        for (int k = 0; k < ss.cascades; ++k) {
            shadowMap_->fit(k, probe_m, cascadeFar_m(ss, k, ss.cascades), sky_.lightDir);
            scene_->buildCasters(probe_m, shadowMap_->casterViewProj(k, probe_m),
                                 shadowMap_->texel_m(k), casters_);
            shadowStats_.triangles += shadowMap_->render(k, *drawer_, casters_, probe_m);
        }
        ++shadowStats_.renders;
        shadowStats_.render_ms +=
            std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
        binding.texture = shadowMap_->texture();
        binding.constants = shadowMap_->constants(probe_m, ss.cascades, ss.pcf,
                                                  ss.normalOffset_texels, ss.depthBias_texels);
        return binding;
    }
    if (!ss.captures) return binding;
    if (!shadowMap_) {
        shadowMap_ = std::make_unique<ShadowMap>(ss.captureMaps, ss.captureMapSize);
        cells_.assign(std::size_t(ss.captureMaps), RegionCell{});
    }
    // The probe's cell: a square of side sqrt 2 (region - tree range), so the region around its
    // centre holds every tree within the capture's tree range of any probe in it.
    const double treeRange_m = scene_->settings().captureTreeRange_m;
    const double cell_m = std::max(10.0, std::sqrt(2.0) * (ss.captureRegion_m - treeRange_m));
    const std::int64_t ci = std::int64_t(std::floor(probe_m.x / cell_m));
    const std::int64_t ck = std::int64_t(std::floor(probe_m.z / cell_m));
    int layer = -1, oldest = 0;
    for (int l = 0; l < ss.captureMaps; ++l) {
        const RegionCell& c = cells_[std::size_t(l)];
        if (c.lastUse >= 0 && c.i == ci && c.k == ck) layer = l;
        if (c.lastUse < cells_[std::size_t(oldest)].lastUse) oldest = l;
    }
    // The map's light is that of the current light epoch: the time of day cut into steps in
    // which the sun turns by at most captureRefresh_deg (15 degrees an hour at most), lit at the
    // step's middle. A cell's map is then a function of the cell and the epoch alone, whatever
    // was captured before it (an oracle's captures between the method's change nothing).
    const double step_h = ss.captureRefresh_deg / 15.0;
    const std::int64_t epoch = std::int64_t(std::floor(sky_.timeOfDay_h / step_h));
    if (epoch != lightEpoch_) {
        lightEpoch_ = epoch;
        epochLight_ =
            evaluateSky(scene_->world().sky(), std::fmod((double(epoch) + 0.5) * step_h, 24.0))
                .lightDir;
    }
    if (layer < 0 || cells_[std::size_t(layer)].epoch != epoch) {
        if (layer < 0) layer = oldest;
        const auto t0 = Clock::now();
        const double x = (double(ci) + 0.5) * cell_m, z = (double(ck) + 0.5) * cell_m;
        const glm::dvec3 centre(x, scene_->world().height(x, z), z);
        shadowMap_->fit(layer, centre, ss.captureRegion_m, epochLight_);
        const glm::dvec3 snapped = shadowMap_->centre(layer);
        scene_->buildCaptureCasters(snapped, shadowMap_->casterViewProj(layer, snapped),
                                    shadowMap_->texel_m(layer), casters_);
        shadowStats_.triangles = shadowMap_->render(layer, *drawer_, casters_, snapped);
        ++shadowStats_.renders;
        shadowStats_.render_ms +=
            std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
        cells_[std::size_t(layer)].i = ci;
        cells_[std::size_t(layer)].k = ck;
        cells_[std::size_t(layer)].epoch = epoch;
    }
    cells_[std::size_t(layer)].lastUse = useClock_++;
    binding.texture = shadowMap_->texture();
    binding.constants = shadowMap_->constants(probe_m, 1, ss.pcf, ss.normalOffset_texels,
                                              ss.depthBias_texels, ss.captureBias_m, layer);
    return binding;
}

CubeCaptureStats CubeCaptureGl::capture(const glm::dvec3& position_m, double timeOfDay_h,
                                        CubeFaceMask faces, std::vector<float>& cube) {
    return captureFar(position_m, timeOfDay_h, faces, cube, 0.0);
}

CubeCaptureStats CubeCaptureGl::captureFar(const glm::dvec3& position_m, double timeOfDay_h,
                                           CubeFaceMask faces, std::vector<float>& cube,
                                           double nearRadius_m) {
    return render(position_m, timeOfDay_h, faces, cube, nullptr, nearRadius_m);
}

CubeCaptureStats CubeCaptureGl::captureFarWithDistance(const glm::dvec3& position_m,
                                                       double timeOfDay_h, CubeFaceMask faces,
                                                       std::vector<float>& cube,
                                                       std::vector<float>& distance_m,
                                                       double nearRadius_m) {
    return render(position_m, timeOfDay_h, faces, cube, &distance_m, nearRadius_m);
}

CubeCaptureStats CubeCaptureGl::render(const glm::dvec3& position_m, double timeOfDay_h,
                                       CubeFaceMask faces, std::vector<float>& cube,
                                       std::vector<float>* distance_m, double nearRadius_m) {
    using Clock = std::chrono::steady_clock;
    const auto t0 = Clock::now();
    const size_t faceFloats = size_t(n_) * n_ * 3;
    if (cube.size() != 6 * faceFloats) cube.assign(6 * faceFloats, 0.0f);
    CubeCaptureStats stats;
    faces &= kAllCubeFaces;
    if (!faces) return stats;

    if (timeOfDay_h != sky_.timeOfDay_h) {
        sky_ = evaluateSky(scene_->world().sky(), timeOfDay_h);
        drawer_->setSky(sky_);
    }
    // Surfaces lit by the main light and an ambient: the surface light when one is set (the
    // reference's bounce field, lighting/BounceField.h), else the sky/ground hemisphere.
    const FixedAmbient hemisphere(AmbientMode::Hemisphere, sky_);
    const FieldAmbient field(surfaceLight_);
    const AmbientSource& ambient =
        surfaceLight_ ? static_cast<const AmbientSource&>(field) : hemisphere;
    if (kind_ == CaptureScene::Coarse) scene_->buildCapture(position_m, ambient, list_, nearRadius_m);

    glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
    const ShadowBinding shadows = prepareShadows(position_m);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_.id());
    FrameConstants fc;
    fillSkyConstants(sky_, fc);
    fc.sunDisc = glm::vec4(0.0f, 0.0f, 0.0f, 2.0f);  // disc added on the CPU (step 4)
    fc.fog = glm::vec4(1.0f / 4000.0f, 1.0f, 0.0f, 0.0f);
    int lo = 6, hi = -1;
    for (int f = 0; f < 6; ++f) {
        if (!(faces & cubeFaceBit(f))) continue;
        lo = std::min(lo, f);
        hi = std::max(hi, f);
        glViewport(0, f * n_, n_, n_);
        glEnable(GL_SCISSOR_TEST);
        glScissor(0, f * n_, n_, n_);
        const float clearColour[4] = {0, 0, 0, 0};
        const float far = 0.0f;
        glClearBufferfv(GL_COLOR, 0, clearColour);
        glClearBufferfv(GL_DEPTH, 0, &far);
        glDisable(GL_SCISSOR_TEST);
        fc.viewProj = faceViewProj(f, kCaptureNear_m);
        fc.invViewProj = glm::inverse(fc.viewProj);
        // The full scene is culled to each face's frustum, as the main view culls its own.
        if (kind_ == CaptureScene::Full) scene_->buildView(position_m, fc.viewProj, ambient, list_);
        const DrawList* drawn = &list_;
        if (kind_ == CaptureScene::Coarse) {
            if (faceList_.terrain.size() != list_.terrain.size() || f == lo) {
                faceList_.terrain = list_.terrain;
                faceList_.ambientSets = list_.ambientSets;
                faceList_.vertexIrradiance = list_.vertexIrradiance;
            }
            cullObjectsToFace(list_, f, faceList_);
            drawn = &faceList_;
        }
        stats.triangles =
            std::max(stats.triangles, drawer_->draw(*drawn, fc, false, false, &shadows));
        ++stats.faces;
    }
    // One read-back covering the rendered faces.
    const int rows = (hi - lo + 1) * n_;
    rgba_.resize(size_t(n_) * rows * 4);
    readFramebuffer(fbo_.id(), 0, lo * n_, n_, rows, GL_RGBA, GL_FLOAT, 4, rgba_.data());
    if (distance_m) {
        const size_t face = size_t(n_) * n_;
        if (distance_m->size() != 6 * face) distance_m->assign(6 * face, kFar);
        depthRows_.resize(size_t(n_) * rows);
        readFramebuffer(fbo_.id(), 0, lo * n_, n_, rows, GL_DEPTH_COMPONENT, GL_FLOAT, 4,
                        depthRows_.data());
        for (int f = lo; f <= hi; ++f) {
            if (!(faces & cubeFaceBit(f))) continue;
            for (int j = 0; j < n_; ++j)
                for (int i = 0; i < n_; ++i) {
                    const size_t t = size_t(j) * n_ + i;
                    const size_t read = size_t(f - lo) * face + t;
                    const float depth = depthRows_[read];
                    // Depth 0 is the cleared far plane (sky); a texel the sky shader filled
                    // reads alpha 1 (the sun's test below).
                    const bool sky = !(depth > 0.0f) || rgba_[read * 4 + 3] >= 0.5f;
                    (*distance_m)[size_t(f) * face + t] =
                        sky ? kFar
                            : float(double(kCaptureNear_m) / double(depth) *
                                    glm::length(cubeTexelDirection(f, i, j, n_)));
                }
        }
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);

    for (int f = lo; f <= hi; ++f) {
        if (!(faces & cubeFaceBit(f))) continue;
        const float* src = &rgba_[size_t(f - lo) * n_ * n_ * 4];
        float* dst = &cube[size_t(f) * faceFloats];
        for (size_t t = 0; t < size_t(n_) * n_; ++t) {
            dst[3 * t + 0] = src[4 * t + 0];
            dst[3 * t + 1] = src[4 * t + 1];
            dst[3 * t + 2] = src[4 * t + 2];
        }
    }
    // Step 4: the sun disc's energy into the texel that holds its direction (sunTexel), when
    // that texel sees sky; the texel whoever leaves the sun out is told of (sunDirection).
    if (const std::optional<glm::dvec3> sunDir = sunDirection(timeOfDay_h)) {
        const CubeTexel s = sunTexel(*sunDir, n_);
        const size_t t = size_t(s.j) * n_ + s.i;
        const auto seesSky = [&] {
            return rgba_[(size_t(s.face - lo) * n_ * n_ + t) * 4 + 3] >= 0.5f;
        };
        if ((faces & cubeFaceBit(s.face)) && seesSky()) {  // else hidden by terrain or a tree
            const double sunRadius = scene_->world().sky().sunAngularRadius_rad();
            const glm::vec3 add = sunTexelRadiance(sky_.sunDiscRadiance,
                                                   2.0 * kPi * (1.0 - std::cos(sunRadius)), s, n_);
            float* dst = &cube[size_t(s.face) * faceFloats + 3 * t];
            for (int c = 0; c < 3; ++c) dst[c] += add[c];
        }
    }
    stats.wall_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    lastStats_ = stats;
    return stats;
}

std::optional<glm::dvec3> CubeCaptureGl::sunDirection(double timeOfDay_h) const {
    // The disc is added with the sun's radiance, zero below the horizon: then nothing is added.
    const Sky& sky = scene_->world().sky();
    const glm::vec3 radiance = sky.sunRadiance(timeOfDay_h);
    if (!(radiance.r > 0.0f || radiance.g > 0.0f || radiance.b > 0.0f)) return std::nullopt;
    return sky.sunDirection(timeOfDay_h);
}

std::unique_ptr<MethodAmbienceStages> makeMethodStages(Renderer& renderer,
                                                       const std::string& method,
                                                       const AmbienceVolumeSettings& settings,
                                                       const BaselineSettings& baselines,
                                                       int faceSize) {
    return std::make_unique<MethodAmbienceStages>(
        std::make_unique<CubeCaptureGl>(renderer.scene(), faceSize, renderer.settings().shadows),
        renderer.world(), method,
        settings, baselines);
}

}  // namespace amb
