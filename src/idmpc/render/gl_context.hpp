#pragma once
/// @file gl_context.hpp
/// @brief Off-screen OpenGL context (OSMesa, software rendering) for MuJoCo's renderer.

#include <vector>

// OSMesaContext is `struct osmesa_context*` (GL/osmesa.h); forward-declared to keep GL out
struct osmesa_context;

namespace idmpc::render {

/// @brief An OSMesa context (RGBA, 24-bit depth, 8-bit stencil) with its own colour buffer,
/// current on the constructing thread for its whole lifetime.
///
/// MuJoCo 2.2 loads its GL entry points with its own glad loader: it opens the main program
/// (dlopen(NULL)) and takes the first of eglGetProcAddress, OSMesaGetProcAddress,
/// glXGetProcAddressARB found there. Linking libOSMesa therefore routes mjr_makeContext to
/// OSMesa, as long as libEGL is not loaded in the process; the constructor checks both and
/// throws a std::runtime_error otherwise.
class GlContext {
 public:
  /// @brief Creates the context and a width x height buffer and makes it current.
  /// Throws std::invalid_argument for a bad size and std::runtime_error
  /// ("cannot create an OSMesa off-screen GL context: ...") on failure.
  GlContext(int width, int height);
  ~GlContext();

  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;
  GlContext(GlContext&&) = delete;
  GlContext& operator=(GlContext&&) = delete;

  /// @brief Makes this context current on the calling thread again.
  void make_current();

  int width() const { return width_; }
  int height() const { return height_; }

 private:
  osmesa_context* context_ = nullptr;
  std::vector<unsigned char> buffer_;
  int width_ = 0;
  int height_ = 0;
};

}  // namespace idmpc::render
