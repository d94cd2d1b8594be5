#include "idmpc/render/gl_context.hpp"

#include <GL/osmesa.h>
#include <dlfcn.h>

#include <stdexcept>
#include <string>

namespace idmpc::render {
namespace {

constexpr int kMaxSize = 16384;  // beyond any sensible video frame, well within OSMesa's limit

[[noreturn]] void fail(const std::string& why) {
  throw std::runtime_error("cannot create an OSMesa off-screen GL context: " + why);
}

// MuJoCo 2.2's glad loader resolves GL through the first get-proc-address function visible in
// the main program's global scope, in the order EGL, OSMesa, GLX: check it will pick OSMesa
void check_mujoco_gl_loader() {
  void* self = dlopen(nullptr, RTLD_LAZY);
  if (!self) fail(std::string("dlopen of the main program failed: ") + dlerror());
  const bool has_egl = dlsym(self, "eglGetProcAddress") != nullptr;
  const bool has_osmesa = dlsym(self, "OSMesaGetProcAddress") != nullptr;
  dlclose(self);
  if (has_egl) {
    fail("libEGL is loaded in this process, so MuJoCo 2.2 would load its GL functions through "
         "eglGetProcAddress instead of OSMesa; expected only libOSMesa, got libEGL as well "
         "(do not link libEGL into a program that renders with OSMesa)");
  }
  if (!has_osmesa) {
    fail("OSMesaGetProcAddress is not visible in the program's global symbol scope, so MuJoCo "
         "2.2 cannot find OSMesa; expected libOSMesa linked into the executable (or loaded with "
         "RTLD_GLOBAL), got it missing");
  }
}

}  // namespace

GlContext::GlContext(int width, int height) : width_(width), height_(height) {
  if (width < 1 || height < 1 || width > kMaxSize || height > kMaxSize) {
    throw std::invalid_argument("off-screen buffer size: expected 1.." + std::to_string(kMaxSize) +
                                " x 1.." + std::to_string(kMaxSize) + " pixels, got " +
                                std::to_string(width) + " x " + std::to_string(height));
  }
  check_mujoco_gl_loader();

  // compatibility profile: MuJoCo 2.2 draws with the fixed-function pipeline
  const int attribs[] = {OSMESA_FORMAT,       OSMESA_RGBA,
                         OSMESA_DEPTH_BITS,   24,
                         OSMESA_STENCIL_BITS, 8,
                         OSMESA_ACCUM_BITS,   0,
                         OSMESA_PROFILE,      OSMESA_COMPAT_PROFILE,
                         0};
  context_ = OSMesaCreateContextAttribs(attribs, nullptr);
  if (!context_) fail("OSMesaCreateContextAttribs returned NULL (RGBA, depth 24, stencil 8)");

  buffer_.resize(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 4);
  try {
    make_current();
  } catch (...) {
    OSMesaDestroyContext(context_);
    throw;
  }
}

GlContext::~GlContext() {
  if (OSMesaGetCurrentContext() == context_) {
    OSMesaMakeCurrent(nullptr, nullptr, GL_UNSIGNED_BYTE, 0, 0);
  }
  OSMesaDestroyContext(context_);
}

void GlContext::make_current() {
  if (!OSMesaMakeCurrent(context_, buffer_.data(), GL_UNSIGNED_BYTE, width_, height_)) {
    fail("OSMesaMakeCurrent failed for a " + std::to_string(width_) + " x " +
         std::to_string(height_) + " RGBA buffer");
  }
}

}  // namespace idmpc::render
