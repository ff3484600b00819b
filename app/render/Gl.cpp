// Gl.cpp — GL object owners, shader loading with includes, read-back.
#include "app/render/Gl.h"

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include <glm/gtc/type_ptr.hpp>

#include "world/DataPaths.h"
#include "world/Error.h"
#include "world/TextFile.h"

namespace amb {

void glDeleteBufferName(GLuint id) {
    glDeleteBuffers(1, &id);
}
void glDeleteVertexArrayName(GLuint id) {
    glDeleteVertexArrays(1, &id);
}
void glDeleteTextureName(GLuint id) {
    glDeleteTextures(1, &id);
}
void glDeleteFramebufferName(GLuint id) {
    glDeleteFramebuffers(1, &id);
}
void glDeleteProgramName(GLuint id) {
    glDeleteProgram(id);
}

GlBuffer makeBuffer(const void* data, size_t bytes, GLbitfield flags) {
    GLuint id = 0;
    glCreateBuffers(1, &id);
    glNamedBufferStorage(id, GLsizeiptr(bytes > 0 ? bytes : 4), bytes > 0 ? data : nullptr, flags);
    return GlBuffer(id);
}

GlVertexArray makeVertexArray() {
    GLuint id = 0;
    glCreateVertexArrays(1, &id);
    return GlVertexArray(id);
}

GlTexture makeTexture2D(GLenum internalFormat, int width, int height, int levels) {
    GLuint id = 0;
    glCreateTextures(GL_TEXTURE_2D, 1, &id);
    glTextureStorage2D(id, levels, internalFormat, width, height);
    return GlTexture(id);
}

// ---- Shader files ----------------------------------------------------------------------------

static std::string& shaderDirOverride() {
    static std::string dir;
    return dir;
}

void setShaderDirectory(const std::string& dir) {
    shaderDirOverride() = dir;
}

std::string shaderDirectory() {
    if (!shaderDirOverride().empty()) return shaderDirOverride();
    if (const char* env = std::getenv("AMBIENCE_SHADER_DIR"); env && *env) return env;
    // The data folders (world/DataPaths.h): P/share/ambience/shaders installed, build/shaders
    // in the build tree; when neither exists, the build tree's place names the missing file.
    if (std::string dir = findDataFile("shaders"); !dir.empty()) return dir;
    const std::string exe = executableDirectory();
    return exe.empty() ? std::string("shaders")
                       : (std::filesystem::path(exe).parent_path() / "shaders").string();
}

static std::string readText(const std::string& path) {
    if (access(path.c_str(), R_OK) != 0)
        throw InputError(path, "cannot read shader file (set AMBIENCE_SHADER_DIR or --shaders)");
    return readTextFile(path, "shader file", std::size_t(1) << 20);
}

// The first non-empty line of a GL info log, so that a broken shader is one line on stderr.
static std::string firstLogLine(const char* log) {
    std::istringstream in(log);
    std::string line;
    while (std::getline(in, line)) {
        const auto a = line.find_first_not_of(" \t\r"), b = line.find_last_not_of(" \t\r");
        if (a != std::string::npos) return line.substr(a, b - a + 1);
    }
    return "no log";
}

static void appendResolved(const std::string& file, std::set<std::string>& seen, std::string& out) {
    if (!seen.insert(file).second) return;  // each include once
    std::istringstream in(readText(shaderDirectory() + "/" + file));
    std::string line;
    while (std::getline(in, line)) {
        const auto first = line.find_first_not_of(" \t");
        const std::string t = first == std::string::npos ? "" : line.substr(first);
        if (t.rfind("#extension GL_GOOGLE_include_directive", 0) == 0) {
            out += "\n";  // keep line numbers of the including file
            continue;
        }
        if (t.rfind("#include", 0) == 0) {
            const auto a = t.find('"'), b = t.rfind('"');
            if (a == std::string::npos || b <= a) throw InputError(file, "malformed #include");
            appendResolved(t.substr(a + 1, b - a - 1), seen, out);
            continue;
        }
        out += line;
        out += '\n';
    }
}

std::string loadShaderSource(const std::string& file) {
    std::set<std::string> seen;
    std::string out;
    appendResolved(file, seen, out);
    return out;
}

static GLuint compile(GLenum stage, const std::string& file) {
    const std::string src = loadShaderSource(file);
    const GLuint s = glCreateShader(stage);
    const char* p = src.c_str();
    glShaderSource(s, 1, &p, nullptr);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[4096] = {};
        glGetShaderInfoLog(s, sizeof(log), nullptr, log);
        glDeleteShader(s);
        // The shaders are files read at run time (--shaders): a broken one is bad input.
        throw InputError(shaderDirectory() + "/" + file,
                         "shader does not compile: " + firstLogLine(log));
    }
    return s;
}

GlProgram::GlProgram(const std::string& vertexFile, const std::string& fragmentFile) {
    const GLuint vs = compile(GL_VERTEX_SHADER, vertexFile);
    GLuint fs = 0;
    try {
        fs = compile(GL_FRAGMENT_SHADER, fragmentFile);
    } catch (...) {
        glDeleteShader(vs);
        throw;
    }
    program_ = GlName<glDeleteProgramName>(glCreateProgram());
    glAttachShader(id(), vs);
    glAttachShader(id(), fs);
    glLinkProgram(id());
    glDeleteShader(vs);
    glDeleteShader(fs);
    GLint ok = 0;
    glGetProgramiv(id(), GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[4096] = {};
        glGetProgramInfoLog(id(), sizeof(log), nullptr, log);
        throw InputError(shaderDirectory() + "/" + vertexFile + " + " + fragmentFile,
                         "shaders do not link: " + firstLogLine(log));
    }
}

void GlProgram::set(const char* name, const glm::vec3& v) const {
    glProgramUniform3fv(id(), uniform(name), 1, glm::value_ptr(v));
}
void GlProgram::set(const char* name, const glm::vec4& v) const {
    glProgramUniform4fv(id(), uniform(name), 1, glm::value_ptr(v));
}
void GlProgram::set(const char* name, const glm::mat4& m) const {
    glProgramUniformMatrix4fv(id(), uniform(name), 1, GL_FALSE, glm::value_ptr(m));
}

// ---- Read-back -------------------------------------------------------------------------------

void readFramebuffer(GLuint framebuffer, int x, int y, int width, int height, GLenum format,
                     GLenum type, int packAlignment, void* out) {
    glFinish();  // see Gl.h: glReadPixels alone can read a frame still being drawn
    glBindFramebuffer(GL_READ_FRAMEBUFFER, framebuffer);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glPixelStorei(GL_PACK_ALIGNMENT, packAlignment);
    glReadPixels(x, y, width, height, format, type, out);
}

std::vector<unsigned char> readPixelsRgb8(GLuint framebuffer, int width, int height) {
    std::vector<unsigned char> rgba(size_t(width) * height * 4), rgb(size_t(width) * height * 3);
    readFramebuffer(framebuffer, 0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, 1, rgba.data());
    for (int y = 0; y < height; ++y) {
        const unsigned char* src = &rgba[size_t(height - 1 - y) * width * 4];
        unsigned char* dst = &rgb[size_t(y) * width * 3];
        for (int x = 0; x < width; ++x) {
            dst[3 * x + 0] = src[4 * x + 0];
            dst[3 * x + 1] = src[4 * x + 1];
            dst[3 * x + 2] = src[4 * x + 2];
        }
    }
    return rgb;
}

std::vector<float> readPixelsRgb32f(GLuint framebuffer, int x, int y, int width, int height) {
    std::vector<float> rgb(size_t(width) * height * 3);
    readFramebuffer(framebuffer, x, y, width, height, GL_RGB, GL_FLOAT, 1, rgb.data());
    return rgb;
}

}  // namespace amb
