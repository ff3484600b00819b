// Gl.h — small RAII owners for GL objects, shader programs loaded from shaders/, and read-back.
// Include this (it includes glad) before any other GL header.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <glad/gl.h>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "app/render/ShaderDirectory.h"

namespace amb {

// One GL object name with its delete function; movable, not copyable.
template <void (*Delete)(GLuint)>
class GlName {
  public:
    GlName() = default;
    explicit GlName(GLuint id) : id_(id) {}
    GlName(GlName&& o) noexcept : id_(std::exchange(o.id_, 0)) {}
    GlName& operator=(GlName&& o) noexcept {
        if (this != &o) {
            reset();
            id_ = std::exchange(o.id_, 0);
        }
        return *this;
    }
    GlName(const GlName&) = delete;
    GlName& operator=(const GlName&) = delete;
    ~GlName() { reset(); }
    void reset() {
        if (id_) Delete(id_);
        id_ = 0;
    }
    GLuint id() const { return id_; }
    explicit operator bool() const { return id_ != 0; }

  private:
    GLuint id_ = 0;
};

void glDeleteBufferName(GLuint id);
void glDeleteVertexArrayName(GLuint id);
void glDeleteTextureName(GLuint id);
void glDeleteFramebufferName(GLuint id);
void glDeleteProgramName(GLuint id);

using GlBuffer = GlName<glDeleteBufferName>;
using GlVertexArray = GlName<glDeleteVertexArrayName>;
using GlTexture = GlName<glDeleteTextureName>;
using GlFramebuffer = GlName<glDeleteFramebufferName>;

GlBuffer makeBuffer(const void* data, size_t bytes, GLbitfield flags = 0);
GlVertexArray makeVertexArray();
GlTexture makeTexture2D(GLenum internalFormat, int width, int height, int levels = 1);

// Reads a shader file and resolves `#include "name"` lines against the shader folder (the same
// GL_GOOGLE_include_directive syntax glslangValidator checks at build time).
std::string loadShaderSource(const std::string& file);

// A linked program built from shader files in shaderDirectory(); throws std::runtime_error with
// the GL info log on a compile or link error.
class GlProgram {
  public:
    GlProgram() = default;
    GlProgram(const std::string& vertexFile, const std::string& fragmentFile);
    GLuint id() const { return program_.id(); }
    GLint uniform(const char* name) const { return glGetUniformLocation(program_.id(), name); }
    void use() const { glUseProgram(program_.id()); }
    void set(const char* name, float v) const { glProgramUniform1f(id(), uniform(name), v); }
    void set(const char* name, int v) const { glProgramUniform1i(id(), uniform(name), v); }
    void set(const char* name, const glm::vec3& v) const;
    void set(const char* name, const glm::vec4& v) const;
    void set(const char* name, const glm::mat4& m) const;

  private:
    GlName<glDeleteProgramName> program_;
};

// Reads the rectangle (x, y, width, height) of `framebuffer`'s colour attachment 0, or of its
// depth with format GL_DEPTH_COMPONENT, into `out` as `format` and `type`, rows bottom-up as GL
// gives them, each row aligned to `packAlignment` bytes; leaves `framebuffer` bound for reading.
// Every read-back of a rendered image goes through here: it waits for all GL commands issued so
// far (glFinish) before it reads. glReadPixels alone should, but Mesa's llvmpipe (seen with
// 22.3.6) rasterizes a frame on its own threads while the caller goes on, and its read-back does
// not always wait for them once the image is no longer bound for drawing. After two tone-mapped
// renders (Ambient, then Shaded, each read back), a screen-witness render read back at once came
// back in part or whole as the target held before (the last render's pixels or only the clear:
// alpha 0, so drawn terrain and trees were read as sky), in 26 of 28 processes here
// (Renderer.ReadBacksWaitForTheRenderTheyRead), more often when other load slowed the
// rasterizer threads; through OSMesa (llvmpipe too) just the same. The image itself was right:
// the same target read again after glFinish is whole, and rasterizing on the calling thread
// (LP_NUM_THREADS=0) never showed it; it was no GL state left between passes (unbinding the HDR
// target from the tone mapping's texture unit changed nothing). Keeping the framebuffer bound
// for drawing while reading also made llvmpipe wait, but that leans on how it tracks its work;
// glFinish says what is meant.
void readFramebuffer(GLuint framebuffer, int x, int y, int width, int height, GLenum format,
                     GLenum type, int packAlignment, void* out);
// Reads the RGBA8 colour attachment 0 of `framebuffer` (rows bottom-up in GL) into top-down RGB.
std::vector<unsigned char> readPixelsRgb8(GLuint framebuffer, int width, int height);
// Reads an RGBA32F attachment into float RGB, rows in GL order (row 0 = first row, bottom).
std::vector<float> readPixelsRgb32f(GLuint framebuffer, int x, int y, int width, int height);

}  // namespace amb
