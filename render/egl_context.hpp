#pragma once
// A headless EGL display + OpenGL 3.3 core context, no surface (EGL_KHR_surfaceless_context):
// rendering goes to framebuffer objects. Two platforms:
//   device       EGL_EXT_platform_device: a display on an EGL device from eglQueryDevicesEXT
//                (a GPU driver; NVIDIA's or Mesa's DRM devices);
//   surfaceless  EGL_MESA_platform_surfaceless: Mesa without any window system (llvmpipe
//                where there is no GPU).
// `auto` tries every device that is not Mesa's software device (EGL_MESA_device_software)
// and falls back to surfaceless. The choice comes from the option or, for
// EglPlatform::kFromEnvironment, from SHELFCROSS_EGL=auto|device|surfaceless (unset: auto).

#include <string>

namespace shelfcross::render {

enum class EglPlatform { kFromEnvironment, kAuto, kDevice, kSurfaceless };

class EglContext {
 public:
  /// Throws RenderError with the EGL error and the platforms tried if no context can be made.
  explicit EglContext(EglPlatform platform);
  ~EglContext();
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  /// Makes this context current on the calling thread (no-op if it already is). Throws
  /// RenderError with the EGL error when EGL refuses.
  void make_current();
  /// Releases the context from the calling thread if it is current there.
  void release();

  /// "device" or "surfaceless".
  const std::string& platform_name() const { return platform_name_; }
  /// EGL vendor and version strings of the display, e.g. "Mesa Project, 1.5".
  const std::string& egl_vendor() const { return egl_vendor_; }

 private:
  bool try_display(void* display, const std::string& name, std::string& why);

  void* display_ = nullptr;  // EGLDisplay
  void* context_ = nullptr;  // EGLContext
  std::string platform_name_;
  std::string egl_vendor_;
};

}  // namespace shelfcross::render
