// A headless OpenGL 4.3 core context through EGL (surfaceless Mesa platform, else an EGL device,
// else the default display), for the GPU tests. On llvmpipe this runs without any GPU.
#pragma once

#include <string>

namespace vff::harness {

struct HeadlessGl {
  bool ok = false;
  std::string error;     // why no context could be made (when !ok)
  std::string renderer;  // GL_RENDERER and GL_VERSION (when ok)
};

// Makes (once per process) a GL 4.3 core context current on the calling thread.
const HeadlessGl& headlessGl();

// Compiles and links a compute program from "#version 430", `defines`, gpu/glsl/vff_query.glsl
// and `body` (GL has no #include). Returns the program, or 0 with the compile or link log in *log.
unsigned buildQueryProgram(const std::string& defines, const std::string& body, std::string* log);

// Compiles and links a compute program from its whole text. Returns 0 with the log on failure.
unsigned buildProgram(const std::string& source, std::string* log);

// The text of gpu/glsl/NAME.
std::string readGlsl(const std::string& name);

}  // namespace vff::harness
