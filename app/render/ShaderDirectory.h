// ShaderDirectory.h — where the renderer loads its GLSL from (Gl.cpp), without GL: the commands
// set it from their --shaders option.
#pragma once

#include <string>

namespace amb {

// The folder the renderer loads GLSL from: $AMBIENCE_SHADER_DIR if set, else the first
// `shaders` data folder (world/DataPaths.h): P/share/ambience/shaders for an installed program,
// <executable dir>/../shaders in the build tree.
std::string shaderDirectory();
void setShaderDirectory(const std::string& dir);  // overrides both (the --shaders option)

}  // namespace amb
