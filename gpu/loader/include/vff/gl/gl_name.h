// vff/gl/gl_name.h - the owner of one OpenGL object name (a buffer or a texture): the object is
// deleted when its owner is destroyed, reset or assigned over, so that a class holding GL objects
// (GpuField, GpuScene) needs no move or release code of its own.
//
//   vff::gl::GlName buffer(vff::gl::GlName::Kind::kBuffer);
//   glGenBuffers(1, buffer.out());         // the name to fill (the old object, if any, is deleted)
//   glBindBuffer(GL_UNIFORM_BUFFER, buffer.get());
//   // ~GlName: glDeleteBuffers (the context must be current)
//
// Move-only; a moved-from GlName holds no object. Deleting needs the GL context the object was
// made in to be current on the calling thread, as for any GL call.
#pragma once

#include <cstdint>
#include <utility>

namespace vff::gl {

class GlName {
 public:
  enum class Kind : uint8_t { kBuffer, kTexture };

  GlName() = default;
  explicit GlName(Kind kind) noexcept : kind_(kind) {}
  GlName(GlName&& o) noexcept : name_(std::exchange(o.name_, 0)), kind_(o.kind_) {}
  GlName& operator=(GlName&& o) noexcept {
    if (this != &o) {
      reset();
      name_ = std::exchange(o.name_, 0);
      kind_ = o.kind_;
    }
    return *this;
  }
  GlName(const GlName&) = delete;
  GlName& operator=(const GlName&) = delete;
  ~GlName() { reset(); }

  // Deletes the object now, if there is one (glDeleteBuffers or glDeleteTextures).
  void reset() noexcept;
  // The object's name for a function that makes one (glGenBuffers(1, n.out())): the old object is
  // deleted first.
  uint32_t* out() noexcept {
    reset();
    return &name_;
  }
  uint32_t get() const noexcept { return name_; }  // 0: no object
  explicit operator bool() const noexcept { return name_ != 0; }

 private:
  uint32_t name_ = 0;
  Kind kind_ = Kind::kBuffer;
};

}  // namespace vff::gl
