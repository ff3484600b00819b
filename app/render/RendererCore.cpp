// RendererCore.cpp — programs, sky evaluation, meshes and the shared draw of a DrawList.
#include "app/render/RendererCore.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "world/Conventions.h"

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
    for (std::size_t i = 0; i + 2 < mesh.positions.size(); i += 3)
        m.boundRadius_m = std::max(
            m.boundRadius_m, glm::length(glm::vec3(mesh.positions[i], mesh.positions[i + 1],
                                                   mesh.positions[i + 2])));
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
    // Sky detail per vertex (terrain; world/TerrainPatch.h).
    if (!mesh.skyDetail.empty()) {
        m.skyDetail = makeBuffer(mesh.skyDetail.data(), mesh.skyDetail.size() * sizeof(float));
        glVertexArrayVertexBuffer(vao, 6, m.skyDetail.id(), 0, 2 * sizeof(float));
        glEnableVertexArrayAttrib(vao, 6);
        glVertexArrayAttribFormat(vao, 6, 2, GL_FLOAT, GL_FALSE, 0);
        glVertexArrayAttribBinding(vao, 6, 6);
    }
    // A plant's own crown's occlusion per vertex (world/WorldMesh.h); disabled, the attribute
    // reads 0 (the ambient kept whole).
    if (!mesh.occlusion.empty()) {
        m.occlusion = makeBuffer(mesh.occlusion.data(), mesh.occlusion.size() * sizeof(float));
        glVertexArrayVertexBuffer(vao, 7, m.occlusion.id(), 0, sizeof(float));
        glEnableVertexArrayAttrib(vao, 7);
        glVertexArrayAttribFormat(vao, 7, 1, GL_FLOAT, GL_FALSE, 0);
        glVertexArrayAttribBinding(vao, 7, 7);
    }
    glVertexArrayElementBuffer(vao, m.indices.id());
    return m;
}

// ---- Sky constants ---------------------------------------------------------------------------

void fillSkyConstants(const SkyLighting& sky, FrameConstants& fc) {
    fc.lightDir = glm::vec4(sky.lightDir, 0.0f);
    fc.lightIrradiance = glm::vec4(sky.lightIrradiance, 0.0f);
    fc.sunDisc = glm::vec4(sky.sunDiscRadiance, sky.sunCosRadius);
    fc.sunAzimuth = glm::vec4(sky.sunAzimuth, 0.0f);
    fc.fogToward = glm::vec4(sky.horizonToward, 0.0f);
    fc.fogAway = glm::vec4(sky.horizonAway, 0.0f);
}

// ---- SceneDrawer -----------------------------------------------------------------------------

SceneDrawer::SceneDrawer()
    : terrain_("terrain.vert", "terrain.frag"),
      object_("object.vert", "object.frag"),
      sky_("fullscreen.vert", "sky.frag"),
      tonemap_("fullscreen.vert", "tonemap.frag"),
      caster_("shadow_caster.vert", "shadow_caster.frag") {
    constants_ = makeBuffer(nullptr, sizeof(FrameConstants), GL_DYNAMIC_STORAGE_BIT);
    shadowConstants_ = makeBuffer(nullptr, sizeof(ShadowConstants), GL_DYNAMIC_STORAGE_BIT);
    // A depth array of one texel at depth 1 (never nearer the light than a receiver).
    GLuint none = 0;
    glCreateTextures(GL_TEXTURE_2D_ARRAY, 1, &none);
    noShadow_ = GlTexture(none);
    glTextureStorage3D(none, 1, GL_DEPTH_COMPONENT32F, 1, 1, 1);
    const float one = 1.0f;
    glTextureSubImage3D(none, 0, 0, 0, 0, 1, 1, 1, GL_DEPTH_COMPONENT, GL_FLOAT, &one);
    glTextureParameteri(none, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    glTextureParameteri(none, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
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
    terrainSkyDetail_ = terrain_.uniform("uSkyDetail");
    terrainRoad_ = terrain_.uniform("uRoad");
    objectSimplified_ = object_.uniform("uSimplified");
    casterOrigin_ = caster_.uniform("uOrigin");
    casterInstanced_ = caster_.uniform("uInstanced");
}

void SceneDrawer::setSky(const SkyLighting& sky) {
    glTextureSubImage2D(skyTexture_.id(), 0, 0, 0, SkyLighting::kWidth, SkyLighting::kHeight,
                        GL_RGB, GL_FLOAT, sky.texture.data());
}

// One instanced draw per batch of `list`, reading the instances uploadInstances put in one
// buffer, in the same order; `simplifiedLocation` (or -1) is told which batches are simplified.
// Returns the triangles drawn.
std::size_t SceneDrawer::drawObjectBatches(const DrawList& list, GLint simplifiedLocation,
                                           PassTimer* timer) {
    std::size_t triangles = 0, offset = 0, passTriangles = 0;
    int pass = -1;
    for (const ObjectBatch& b : list.objects) {
        if (b.instances.empty()) continue;
        const RenderPass bp = b.vehicle ? RenderPass::Car : RenderPass::Plants;
        if (timer && int(bp) != pass) {
            if (pass >= 0) timer->end(passTriangles);
            timer->begin(bp);
            pass = int(bp), passTriangles = 0;
        }
        passTriangles += b.mesh->triangles() * b.instances.size();
        const GLuint vao = b.mesh->vao.id();
        glVertexArrayVertexBuffer(vao, 1, instances_.id(),
                                  GLintptr(offset * sizeof(ObjectInstance)),
                                  sizeof(ObjectInstance));
        glEnableVertexArrayAttrib(vao, 3);
        glEnableVertexArrayAttrib(vao, 4);
        if (simplifiedLocation >= 0) glUniform1i(simplifiedLocation, b.simplified ? 1 : 0);
        glBindVertexArray(vao);
        glDrawElementsInstanced(GL_TRIANGLES, b.mesh->indexCount, GL_UNSIGNED_INT, nullptr,
                                GLsizei(b.instances.size()));
        triangles += b.mesh->triangles() * b.instances.size();
        offset += b.instances.size();
    }
    if (timer && pass >= 0) timer->end(passTriangles);
    return triangles;
}

std::size_t SceneDrawer::uploadInstances(const DrawList& list) {
    std::size_t instanceCount = 0;
    for (const ObjectBatch& b : list.objects) instanceCount += b.instances.size();
    if (instanceCount == 0) return 0;
    if (instanceCount > instanceCapacity_) {
        instanceCapacity_ = std::max<std::size_t>(instanceCount * 2, 1024);
        instances_ = makeBuffer(nullptr, instanceCapacity_ * sizeof(ObjectInstance),
                                GL_DYNAMIC_STORAGE_BIT);
    }
    std::size_t offset = 0;
    for (const ObjectBatch& b : list.objects) {
        if (b.instances.empty()) continue;
        glNamedBufferSubData(instances_.id(), GLintptr(offset * sizeof(ObjectInstance)),
                             GLsizeiptr(b.instances.size() * sizeof(ObjectInstance)),
                             b.instances.data());
        offset += b.instances.size();
    }
    return instanceCount;
}

std::size_t SceneDrawer::draw(const DrawList& list, const FrameConstants& constants,
                              bool cullBackFaces, bool frontFaceClockwise,
                              const ShadowBinding* shadows) {
    std::size_t triangles = 0;
    glNamedBufferSubData(constants_.id(), 0, sizeof(FrameConstants), &constants);
    glBindBufferBase(GL_UNIFORM_BUFFER, 0, constants_.id());
    glBindTextureUnit(0, skyTexture_.id());
    // The shadows of the direct term (shaders/shadow.glsl): binding 2, texture unit 2.
    const bool shadowed = shadows && shadows->texture && shadows->constants.params.x > 0.5f;
    ShadowConstants sc = shadowed ? shadows->constants : ShadowConstants{};
    glNamedBufferSubData(shadowConstants_.id(), 0, sizeof(ShadowConstants), &sc);
    glBindBufferBase(GL_UNIFORM_BUFFER, 2, shadowConstants_.id());
    glBindTextureUnit(2, shadowed ? shadows->texture : noShadow_.id());
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
    if (!list.ambientSets.empty() && uploadInstances(list) > 0) {
        if (list.ambientSets.size() > ambientCapacity_) {
            ambientCapacity_ = std::max<std::size_t>(list.ambientSets.size() * 2, 64);
            ambientSets_ =
                makeBuffer(nullptr, ambientCapacity_ * sizeof(AmbientSet), GL_DYNAMIC_STORAGE_BIT);
        }
        glNamedBufferSubData(ambientSets_.id(), 0, list.ambientSets.size() * sizeof(AmbientSet),
                             list.ambientSets.data());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, ambientSets_.id());
        object_.use();
        triangles += drawObjectBatches(list, objectSimplified_, timer_);
    }

    // Terrain patches (and road pieces): one draw each, corner irradiance per patch (or, for
    // road pieces and terrain patches lit per vertex, irradiance per vertex from one buffer for
    // the frame).
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
    // Road pieces before the terrain patches: a road lies on the terrain, so the early depth
    // test then skips shading the terrain under it.
    int pass = -1;
    std::size_t passTriangles = 0;
    for (int roads = 1; roads >= 0; --roads)
    for (const TerrainDraw& d : list.terrain) {
        if (d.road != (roads == 1)) continue;
        const RenderPass dp = d.road ? RenderPass::Roads : RenderPass::Terrain;
        if (timer_ && int(dp) != pass) {
            if (pass >= 0) timer_->end(passTriangles);
            timer_->begin(dp);
            pass = int(dp), passTriangles = 0;
        }
        glUniform3fv(terrainOrigin_, 1, &d.origin.x);
        glUniform4fv(terrainRect_, 1, &d.rect.x);
        glm::vec4 corners[4];
        for (int k = 0; k < 4; ++k) corners[k] = glm::vec4(d.cornerIrradiance[k], 0.0f);
        glUniform4fv(terrainCorners_, 4, &corners[0].x);
        const GLuint vao = d.mesh->vao.id();
        const bool perVertex = d.firstVertexIrradiance >= 0;
        glUniform1i(terrainPerVertex_, perVertex ? 1 : 0);
        glUniform1i(terrainRoad_, d.road ? 1 : 0);
        glUniform1i(terrainSkyDetail_, d.skyDetail && d.mesh->skyDetail.id() != 0 ? 1 : 0);
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
        passTriangles += std::size_t(count) / 3;
    }
    if (timer_ && pass >= 0) timer_->end(passTriangles);

    // Sky last, only where no surface was drawn (depth still 0 = infinitely far).
    if (timer_) timer_->begin(RenderPass::Sky);
    glDisable(GL_CULL_FACE);
    glDepthFunc(GL_GEQUAL);
    glDepthMask(GL_FALSE);
    sky_.use();
    glBindVertexArray(emptyVao_.id());
    glDrawArrays(GL_TRIANGLES, 0, 3);
    if (timer_) timer_->end(1);
    glDepthMask(GL_TRUE);
    glBindVertexArray(0);
    return triangles;
}

std::size_t SceneDrawer::drawDepth(const DrawList& list, const glm::mat4& viewProj) {
    std::size_t triangles = 0;
    FrameConstants fc;
    fc.viewProj = viewProj;
    glNamedBufferSubData(constants_.id(), 0, sizeof(FrameConstants), &fc);
    glBindBufferBase(GL_UNIFORM_BUFFER, 0, constants_.id());
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glDisable(GL_CULL_FACE);  // crowns and leaves are thin: both faces cast
    caster_.use();
    if (uploadInstances(list) > 0) {
        glUniform1i(casterInstanced_, 1);
        triangles += drawObjectBatches(list, -1);
    }
    glUniform1i(casterInstanced_, 0);
    for (const TerrainDraw& d : list.terrain) {
        glUniform3fv(casterOrigin_, 1, &d.origin.x);
        glBindVertexArray(d.mesh->vao.id());
        const GLsizei count = d.indexCount > 0 ? GLsizei(d.indexCount) : d.mesh->indexCount;
        glDrawElements(GL_TRIANGLES, count, GL_UNSIGNED_INT,
                       reinterpret_cast<const void*>(std::uintptr_t(d.firstIndex) * 4));
        triangles += std::size_t(count) / 3;
    }
    glBindVertexArray(0);
    glDepthFunc(GL_GREATER);
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
