// RendererCore.cpp — programs, sky evaluation, meshes and the shared draw of a DrawList.
#include "app/RendererCore.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "world/Conventions.h"
#include "world/Sky.h"

namespace amb {

glm::mat4 reversedInfinitePerspective(float fovY_rad, float aspect, float near_m) {
    const float f = 1.0f / std::tan(0.5f * fovY_rad);
    glm::mat4 p(0.0f);
    p[0][0] = f / aspect;
    p[1][1] = f;
    p[2][3] = -1.0f;   // w = -z_eye
    p[3][2] = near_m;  // z = near, so depth = near / -z_eye
    return p;
}

// ---- GlMesh ----------------------------------------------------------------------------------

GlMesh uploadMesh(const WorldMesh& mesh) {
    GlMesh m;
    m.positions = makeBuffer(mesh.positions.data(), mesh.positions.size() * sizeof(float));
    m.normals = makeBuffer(mesh.normals.data(), mesh.normals.size() * sizeof(float));
    m.albedo = makeBuffer(mesh.albedo.data(), mesh.albedo.size() * sizeof(float));
    m.indices = makeBuffer(mesh.indices.data(), mesh.indices.size() * sizeof(std::uint32_t));
    m.indexCount = GLsizei(mesh.indices.size());
    m.vao = makeVertexArray();
    const GLuint vao = m.vao.id();
    const GLuint buffers[3] = {m.positions.id(), m.normals.id(), m.albedo.id()};
    for (GLuint a = 0; a < 3; ++a) {
        glVertexArrayVertexBuffer(vao, a + 2, buffers[a], 0, 3 * sizeof(float));
        glEnableVertexArrayAttrib(vao, a);
        glVertexArrayAttribFormat(vao, a, 3, GL_FLOAT, GL_FALSE, 0);
        glVertexArrayAttribBinding(vao, a, a + 2);
    }
    // Instance attributes (objects only; terrain leaves them disabled).
    glVertexArrayBindingDivisor(vao, 1, 1);
    glVertexArrayAttribFormat(vao, 3, 4, GL_FLOAT, GL_FALSE, 0);
    glVertexArrayAttribBinding(vao, 3, 1);
    glVertexArrayAttribFormat(vao, 4, 2, GL_FLOAT, GL_FALSE, 16);
    glVertexArrayAttribBinding(vao, 4, 1);
    // Irradiance per vertex (road pieces; SceneDrawer::draw binds and enables it per draw).
    glVertexArrayAttribFormat(vao, 5, 3, GL_FLOAT, GL_FALSE, 0);
    glVertexArrayAttribBinding(vao, 5, 5);
    glVertexArrayElementBuffer(vao, m.indices.id());
    return m;
}

// ---- Sky -------------------------------------------------------------------------------------

SkyLighting evaluateSky(const Sky& sky, double timeOfDay_h) {
    SkyLighting s;
    s.timeOfDay_h = timeOfDay_h;
    const SkyState state = sky.state(timeOfDay_h);
    const DirectionalLight light = sky.mainLight(timeOfDay_h);
    s.lightDir = glm::vec3(light.direction);
    s.lightIrradiance = light.irradiance;
    s.sunDiscRadiance = sky.sunRadiance(timeOfDay_h);
    s.sunCosRadius = float(std::cos(sky.sunAngularRadius_rad()));
    const glm::dvec3 sunDir = sky.sunDirection(timeOfDay_h);
    glm::dvec3 az(sunDir.x, 0.0, sunDir.z);
    az = glm::length(az) > 1e-9 ? glm::normalize(az) : glm::dvec3(0.0, 0.0, 1.0);
    s.sunAzimuth = glm::vec3(az);
    const double up = std::sin(2.0 * kPi / 180.0), across = std::cos(2.0 * kPi / 180.0);
    s.horizonToward = sky.radiance(glm::dvec3(az.x * across, up, az.z * across), state);
    s.horizonAway = sky.radiance(glm::dvec3(-az.x * across, up, -az.z * across), state);

    // Upper hemisphere: the sky model, texel by texel, with sin(theta) dtheta dphi weights.
    const int w = SkyLighting::kWidth, h = SkyLighting::kHeight;
    s.texture.assign(size_t(w) * h * 3, 0.0f);
    glm::dvec3 skySum(0.0), irrUp(0.0);
    double skyWeight = 0.0;
    const double dTheta = kPi / h, dPhi = 2.0 * kPi / w;
    for (int r = 0; r < h / 2; ++r) {
        const double theta = (r + 0.5) * dTheta;
        for (int c = 0; c < w; ++c) {
            const double phi = ((c + 0.5) / w - 0.5) * 2.0 * kPi;
            const glm::dvec3 d(std::sin(theta) * std::sin(phi), std::cos(theta),
                               -std::sin(theta) * std::cos(phi));
            const glm::vec3 L = sky.radiance(d, state);
            std::copy(&L.x, &L.x + 3, &s.texture[(size_t(r) * w + c) * 3]);
            const double dw = std::sin(theta) * dTheta * dPhi;
            skySum += glm::dvec3(L) * dw;
            skyWeight += dw;
            irrUp += glm::dvec3(L) * d.y * dw;
        }
    }
    s.skyMean = glm::vec3(skySum / skyWeight);
    s.skyIrradianceUp = glm::vec3(irrUp);
    // Lower hemisphere: distant ground, Lambertian, lit by the sky and the main light.
    const glm::vec3 groundIrr =
        s.skyIrradianceUp + s.lightIrradiance * std::max(0.0f, s.lightDir.y);
    s.groundMean = SkyLighting::kDistantGroundAlbedo / float(kPi) * groundIrr;
    for (int r = h / 2; r < h; ++r) {
        for (int c = 0; c < w; ++c) {
            std::copy(&s.groundMean.x, &s.groundMean.x + 3, &s.texture[(size_t(r) * w + c) * 3]);
        }
    }
    return s;
}

void SkyLighting::fill(FrameConstants& fc) const {
    fc.lightDir = glm::vec4(lightDir, 0.0f);
    fc.lightIrradiance = glm::vec4(lightIrradiance, 0.0f);
    fc.sunDisc = glm::vec4(sunDiscRadiance, sunCosRadius);
    fc.sunAzimuth = glm::vec4(sunAzimuth, 0.0f);
    fc.fogToward = glm::vec4(horizonToward, 0.0f);
    fc.fogAway = glm::vec4(horizonAway, 0.0f);
}

float exposureFor(const SkyLighting& now, const SkyLighting& noon) {
    auto white = [](const SkyLighting& s) {
        const glm::vec3 e = s.skyIrradianceUp + s.lightIrradiance * std::max(0.0f, s.lightDir.y);
        return luminance(e) / float(kPi);
    };
    const float reference = std::max(white(noon), 1e-6f);
    return 0.6f / std::max(white(now), reference * 1e-3f);
}

// ---- SceneDrawer -----------------------------------------------------------------------------

SceneDrawer::SceneDrawer()
    : terrain_("terrain.vert", "terrain.frag"),
      object_("object.vert", "object.frag"),
      sky_("fullscreen.vert", "sky.frag"),
      tonemap_("fullscreen.vert", "tonemap.frag") {
    constants_ = makeBuffer(nullptr, sizeof(FrameConstants), GL_DYNAMIC_STORAGE_BIT);
    skyTexture_ = makeTexture2D(GL_RGB32F, SkyLighting::kWidth, SkyLighting::kHeight);
    glTextureParameteri(skyTexture_.id(), GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(skyTexture_.id(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(skyTexture_.id(), GL_TEXTURE_WRAP_S, GL_REPEAT);
    glTextureParameteri(skyTexture_.id(), GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    emptyVao_ = makeVertexArray();
    terrainOrigin_ = terrain_.uniform("uOrigin");
    terrainRect_ = terrain_.uniform("uPatchRect");
    terrainCorners_ = terrain_.uniform("uCornerIrradiance");
    terrainPerVertex_ = terrain_.uniform("uVertexIrradiance");
    objectSimplified_ = object_.uniform("uSimplified");
}

void SceneDrawer::setSky(const SkyLighting& sky) {
    glTextureSubImage2D(skyTexture_.id(), 0, 0, 0, SkyLighting::kWidth, SkyLighting::kHeight,
                        GL_RGB, GL_FLOAT, sky.texture.data());
}

std::size_t SceneDrawer::draw(const DrawList& list, const FrameConstants& constants,
                              bool cullBackFaces, bool frontFaceClockwise) {
    std::size_t triangles = 0;
    glNamedBufferSubData(constants_.id(), 0, sizeof(FrameConstants), &constants);
    glBindBufferBase(GL_UNIFORM_BUFFER, 0, constants_.id());
    glBindTextureUnit(0, skyTexture_.id());
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_GREATER);
    glDepthMask(GL_TRUE);
    glFrontFace(frontFaceClockwise ? GL_CW : GL_CCW);
    if (cullBackFaces) {
        glEnable(GL_CULL_FACE);
        glCullFace(GL_BACK);
    } else {
        glDisable(GL_CULL_FACE);
    }

    // Objects first (near trees hide much terrain): one instanced draw per batch; all
    // instances of the frame in one buffer.
    std::size_t instanceCount = 0;
    for (const ObjectBatch& b : list.objects) instanceCount += b.instances.size();
    if (instanceCount > 0 && !list.ambientSets.empty()) {
        if (instanceCount > instanceCapacity_) {
            instanceCapacity_ = std::max<std::size_t>(instanceCount * 2, 1024);
            instances_ = makeBuffer(nullptr, instanceCapacity_ * sizeof(ObjectInstance),
                                    GL_DYNAMIC_STORAGE_BIT);
        }
        if (list.ambientSets.size() > ambientCapacity_) {
            ambientCapacity_ = std::max<std::size_t>(list.ambientSets.size() * 2, 64);
            ambientSets_ =
                makeBuffer(nullptr, ambientCapacity_ * sizeof(AmbientSet), GL_DYNAMIC_STORAGE_BIT);
        }
        glNamedBufferSubData(ambientSets_.id(), 0, list.ambientSets.size() * sizeof(AmbientSet),
                             list.ambientSets.data());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, ambientSets_.id());
        std::size_t offset = 0;
        for (const ObjectBatch& b : list.objects) {
            if (b.instances.empty()) continue;
            glNamedBufferSubData(instances_.id(), GLintptr(offset * sizeof(ObjectInstance)),
                                 GLsizeiptr(b.instances.size() * sizeof(ObjectInstance)),
                                 b.instances.data());
            offset += b.instances.size();
        }
        object_.use();
        offset = 0;
        for (const ObjectBatch& b : list.objects) {
            if (b.instances.empty()) continue;
            const GLuint vao = b.mesh->vao.id();
            glVertexArrayVertexBuffer(vao, 1, instances_.id(),
                                      GLintptr(offset * sizeof(ObjectInstance)),
                                      sizeof(ObjectInstance));
            glEnableVertexArrayAttrib(vao, 3);
            glEnableVertexArrayAttrib(vao, 4);
            glUniform1i(objectSimplified_, b.simplified ? 1 : 0);
            glBindVertexArray(vao);
            glDrawElementsInstanced(GL_TRIANGLES, b.mesh->indexCount, GL_UNSIGNED_INT, nullptr,
                                    GLsizei(b.instances.size()));
            triangles += b.mesh->triangles() * b.instances.size();
            offset += b.instances.size();
        }
    }

    // Terrain patches (and road pieces): one draw each, corner irradiance per patch (or, for
    // road pieces, irradiance per vertex from one buffer for the frame).
    terrain_.use();
    if (!list.vertexIrradiance.empty()) {
        if (list.vertexIrradiance.size() > vertexIrradianceCapacity_) {
            vertexIrradianceCapacity_ =
                std::max<std::size_t>(list.vertexIrradiance.size() * 2, 4096);
            vertexIrradiance_ = makeBuffer(nullptr, vertexIrradianceCapacity_ * sizeof(glm::vec3),
                                           GL_DYNAMIC_STORAGE_BIT);
        }
        glNamedBufferSubData(vertexIrradiance_.id(), 0,
                             GLsizeiptr(list.vertexIrradiance.size() * sizeof(glm::vec3)),
                             list.vertexIrradiance.data());
    }
    for (const TerrainDraw& d : list.terrain) {
        glUniform3fv(terrainOrigin_, 1, &d.origin.x);
        glUniform4fv(terrainRect_, 1, &d.rect.x);
        glm::vec4 corners[4];
        for (int k = 0; k < 4; ++k) corners[k] = glm::vec4(d.cornerIrradiance[k], 0.0f);
        glUniform4fv(terrainCorners_, 4, &corners[0].x);
        const GLuint vao = d.mesh->vao.id();
        const bool perVertex = d.firstVertexIrradiance >= 0;
        glUniform1i(terrainPerVertex_, perVertex ? 1 : 0);
        if (perVertex) {
            glVertexArrayVertexBuffer(vao, 5, vertexIrradiance_.id(),
                                      GLintptr(d.firstVertexIrradiance * sizeof(glm::vec3)),
                                      sizeof(glm::vec3));
            glEnableVertexArrayAttrib(vao, 5);
        }
        glBindVertexArray(vao);
        const GLsizei count = d.indexCount > 0 ? GLsizei(d.indexCount) : d.mesh->indexCount;
        glDrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT,
                       reinterpret_cast<const void*>(std::uintptr_t(d.firstIndex) * 4));
        if (perVertex) glDisableVertexArrayAttrib(vao, 5);
        triangles += std::size_t(count) / 3;
    }

    // Sky last, only where no surface was drawn (depth still 0 = infinitely far).
    glDisable(GL_CULL_FACE);
    glDepthFunc(GL_GEQUAL);
    glDepthMask(GL_FALSE);
    sky_.use();
    glBindVertexArray(emptyVao_.id());
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glDepthMask(GL_TRUE);
    glBindVertexArray(0);
    return triangles;
}

void SceneDrawer::drawTonemap(GLuint hdrTexture, float exposure) {
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    tonemap_.use();
    tonemap_.set("uExposure", exposure);
    glBindTextureUnit(0, hdrTexture);
    glBindVertexArray(emptyVao_.id());
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
}

}  // namespace amb
