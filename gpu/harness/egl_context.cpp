#include "egl_context.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/glcorearb.h>

#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

namespace vff::harness {
namespace {

bool hasExtension(const char* list, const char* name) {
  if (!list) return false;
  const size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n)
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  return false;
}

HeadlessGl make() {
  HeadlessGl out;
  const char* clientExt = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  auto getPlatformDisplay =
      reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
  EGLDisplay dpy = EGL_NO_DISPLAY;
  std::string how;
  if (getPlatformDisplay && hasExtension(clientExt, "EGL_MESA_platform_surfaceless")) {
    dpy = getPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    how = "surfaceless";
  }
  if (dpy == EGL_NO_DISPLAY && getPlatformDisplay && hasExtension(clientExt, "EGL_EXT_platform_device")) {
    auto queryDevices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
    EGLDeviceEXT devices[8];
    EGLint count = 0;
    if (queryDevices && queryDevices(8, devices, &count) && count > 0) {
      dpy = getPlatformDisplay(EGL_PLATFORM_DEVICE_EXT, devices[0], nullptr);
      how = "device";
    }
  }
  if (dpy == EGL_NO_DISPLAY) {
    dpy = eglGetDisplay(EGL_DEFAULT_DISPLAY);
    how = "default";
  }
  if (dpy == EGL_NO_DISPLAY) {
    out.error = "no EGL display (surfaceless, device or default)";
    return out;
  }
  EGLint major = 0, minor = 0;
  if (!eglInitialize(dpy, &major, &minor)) {
    out.error = "eglInitialize failed on the " + how + " display (EGL error 0x" + std::to_string(eglGetError()) + ")";
    return out;
  }
  if (!eglBindAPI(EGL_OPENGL_API)) {
    out.error = "eglBindAPI(EGL_OPENGL_API) failed";
    return out;
  }
  const char* dpyExt = eglQueryString(dpy, EGL_EXTENSIONS);
  EGLConfig config = nullptr;
  const EGLint configAttribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
  EGLint configs = 0;
  if (!eglChooseConfig(dpy, configAttribs, &config, 1, &configs) || configs < 1) {
    if (!hasExtension(dpyExt, "EGL_KHR_no_config_context")) {
      out.error = "no EGL config with EGL_OPENGL_BIT on the " + how + " display";
      return out;
    }
    config = EGL_NO_CONFIG_KHR;
  }
  const EGLint contextAttribs[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 3,
                                   EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
  EGLContext ctx = eglCreateContext(dpy, config, EGL_NO_CONTEXT, contextAttribs);
  if (ctx == EGL_NO_CONTEXT) {
    out.error = "no OpenGL 4.3 core context on the " + how + " display (EGL error 0x" +
                std::to_string(eglGetError()) + ")";
    return out;
  }
  if (!eglMakeCurrent(dpy, EGL_NO_SURFACE, EGL_NO_SURFACE, ctx)) {
    out.error = "eglMakeCurrent without a surface failed (EGL_KHR_surfaceless_context missing?)";
    return out;
  }
  const char* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const char* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  out.renderer = std::string(renderer ? renderer : "?") + ", " + (version ? version : "?") + " (" + how + " EGL display)";
  out.ok = true;
  return out;
}

}  // namespace

const HeadlessGl& headlessGl() {
  static const HeadlessGl gl = make();
  return gl;
}

std::string readGlsl(const std::string& name) {
  std::ifstream include(std::string(VFF_GLSL_DIR) + "/" + name);
  std::stringstream text;
  text << include.rdbuf();
  return text.str();
}

unsigned buildQueryProgram(const std::string& defines, const std::string& body, std::string* log) {
  return buildProgram("#version 430\n" + defines + readGlsl("vff_query.glsl") + body, log);
}

unsigned buildProgram(const std::string& src, std::string* log) {
  const char* p = src.c_str();
  const GLuint sh = glCreateShader(GL_COMPUTE_SHADER);
  glShaderSource(sh, 1, &p, nullptr);
  glCompileShader(sh);
  GLint ok = 0;
  char buf[8192] = {};
  glGetShaderiv(sh, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    glGetShaderInfoLog(sh, sizeof(buf), nullptr, buf);
    glDeleteShader(sh);
    *log = std::string("compile: ") + buf;
    return 0;
  }
  const GLuint prog = glCreateProgram();
  glAttachShader(prog, sh);
  glLinkProgram(prog);
  glDeleteShader(sh);
  glGetProgramiv(prog, GL_LINK_STATUS, &ok);
  if (!ok) {
    glGetProgramInfoLog(prog, sizeof(buf), nullptr, buf);
    glDeleteProgram(prog);
    *log = std::string("link: ") + buf;
    return 0;
  }
  return prog;
}

}  // namespace vff::harness
