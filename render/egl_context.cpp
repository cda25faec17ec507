#include "render/egl_context.hpp"

#include <cstdlib>
#include <cstring>
#include <mutex>
#include <sstream>
#include <vector>

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include "render/render_error.hpp"

namespace shelfcross::render {
namespace {

std::string egl_error_name(EGLint e) {
  switch (e) {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    default: {
      std::ostringstream os;
      os << "EGL error 0x" << std::hex << e;
      return os.str();
    }
  }
}

bool has_extension(const char* list, const char* name) {
  if (list == nullptr) return false;
  const size_t n = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n) {
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  }
  return false;
}

// EGL displays are per (platform, native display), shared by every context of the process.
// A display, once initialised, stays initialised until the process exits: eglTerminate is
// never called. Why (issue 18): with Mesa 22.3 (egl_dri2), terminating the display's last
// user destroys the screen and dlcloses the driver, swrast_dri.so with LLVM; the next
// renderer's eglInitialize maps it again, possibly elsewhere. A thread that used the driver
// and is still exiting (its thread-local destructors), or any pointer kept across the unload,
// then runs code that is no longer there. A general protection fault in swrast_dri.so at an
// offset that is not an instruction boundary (this machine's kernel log: 0x7700dc, inside
// the 5-byte lea at 0x7700d9) is what a jump through such a stale pointer looks like. Both
// reported crashes had renderers of several threads in one process (a campaign's worker
// threads, three co-simulations in threads); the stress test (render/test/renderer_threads_
// test.cpp) did not reproduce it in 27 x 8 rounds of 4 threads nor 10 x 16 rounds of the
// last-user race, so this is the cause as inferred, removed rather than proven. Not unloading
// the driver also keeps its globals mapped, so LeakSanitizer sees what they point to as
// reachable instead of reporting Mesa's driver state as leaked. Cost: one display's state
// (the driver, kept until exit) after the last renderer is gone.
std::mutex g_display_mutex;

bool acquire_display(EGLDisplay d) {
  // eglInitialize is serialised: the first call per display loads the driver.
  std::lock_guard<std::mutex> lock(g_display_mutex);
  EGLint major = 0, minor = 0;
  return eglInitialize(d, &major, &minor) == EGL_TRUE;
}

EglPlatform platform_from_environment() {
  const char* env = std::getenv("SHELFCROSS_EGL");
  if (env == nullptr || *env == '\0' || std::strcmp(env, "auto") == 0) return EglPlatform::kAuto;
  if (std::strcmp(env, "device") == 0) return EglPlatform::kDevice;
  if (std::strcmp(env, "surfaceless") == 0) return EglPlatform::kSurfaceless;
  throw RenderError(std::string("SHELFCROSS_EGL='") + env +
                    "' is not one of auto, device, surfaceless");
}

}  // namespace

bool EglContext::try_display(void* display_ptr, const std::string& name, std::string& why) {
  EGLDisplay d = static_cast<EGLDisplay>(display_ptr);
  if (d == EGL_NO_DISPLAY) {
    why += name + ": no display (" + egl_error_name(eglGetError()) + "); ";
    return false;
  }
  if (!acquire_display(d)) {
    why += name + ": eglInitialize failed (" + egl_error_name(eglGetError()) + "); ";
    return false;
  }
  auto give_up = [&](const std::string& what) {
    why += name + ": " + what + " (" + egl_error_name(eglGetError()) + "); ";
    return false;
  };
  if (!has_extension(eglQueryString(d, EGL_EXTENSIONS), "EGL_KHR_surfaceless_context"))
    return give_up("no EGL_KHR_surfaceless_context");
  if (!eglBindAPI(EGL_OPENGL_API)) return give_up("eglBindAPI(EGL_OPENGL_API) failed");
  // Any surface type: the context renders only into framebuffer objects.
  const EGLint config_attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_SURFACE_TYPE, 0,
                                   EGL_NONE};
  EGLConfig config = nullptr;
  EGLint n_configs = 0;
  if (!eglChooseConfig(d, config_attribs, &config, 1, &n_configs) || n_configs < 1) {
    if (!has_extension(eglQueryString(d, EGL_EXTENSIONS), "EGL_KHR_no_config_context"))
      return give_up("no EGLConfig for desktop OpenGL");
    config = EGL_NO_CONFIG_KHR;
  }
  const EGLint context_attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 3,
                                    EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                    EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
  EGLContext ctx = eglCreateContext(d, config, EGL_NO_CONTEXT, context_attribs);
  if (ctx == EGL_NO_CONTEXT) return give_up("no OpenGL 3.3 core context");
  display_ = d;
  context_ = ctx;
  platform_name_ = name;
  const char* vendor = eglQueryString(d, EGL_VENDOR);
  const char* version = eglQueryString(d, EGL_VERSION);
  egl_vendor_ = std::string(vendor ? vendor : "?") + ", EGL " + (version ? version : "?");
  return true;
}

EglContext::EglContext(EglPlatform platform) {
  if (platform == EglPlatform::kFromEnvironment) platform = platform_from_environment();
  const char* client_ext = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (!has_extension(client_ext, "EGL_EXT_platform_base") || get_platform_display == nullptr)
    throw RenderError("EGL: the EGL library lacks EGL_EXT_platform_base (client extensions: " +
                      std::string(client_ext ? client_ext : "none") + ")");
  std::string why;

  if (platform == EglPlatform::kAuto || platform == EglPlatform::kDevice) {
    auto query_devices =
        reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
    auto query_device_string = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(
        eglGetProcAddress("eglQueryDeviceStringEXT"));
    EGLint n = 0;
    std::vector<EGLDeviceEXT> devices(16);
    if (has_extension(client_ext, "EGL_EXT_platform_device") && query_devices != nullptr &&
        query_device_string != nullptr &&
        query_devices(static_cast<EGLint>(devices.size()), devices.data(), &n)) {
      devices.resize(static_cast<size_t>(n));
      // Hardware devices first; Mesa's software device only when "device" was asked for.
      std::vector<EGLDeviceEXT> order, software;
      for (EGLDeviceEXT dev : devices) {
        const bool is_software =
            has_extension(query_device_string(dev, EGL_EXTENSIONS), "EGL_MESA_device_software");
        (is_software ? software : order).push_back(dev);
      }
      if (platform == EglPlatform::kDevice) order.insert(order.end(), software.begin(), software.end());
      if (order.empty()) why += "device: no hardware EGL device; ";
      for (size_t k = 0; k < order.size() && context_ == nullptr; ++k) {
        try_display(get_platform_display(EGL_PLATFORM_DEVICE_EXT, order[k], nullptr),
                    "device", why);
      }
    } else {
      why += "device: EGL_EXT_platform_device / eglQueryDevicesEXT unavailable; ";
    }
  }
  if (context_ == nullptr &&
      (platform == EglPlatform::kAuto || platform == EglPlatform::kSurfaceless)) {
    if (has_extension(client_ext, "EGL_MESA_platform_surfaceless")) {
      try_display(get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr),
                  "surfaceless", why);
    } else {
      why += "surfaceless: no EGL_MESA_platform_surfaceless; ";
    }
  }
  if (context_ == nullptr)
    throw RenderError("EGL: could not create a headless OpenGL 3.3 core context: " + why +
                      "(install Mesa's libegl-mesa0 and libgl1-mesa-dri for llvmpipe)");
}

EglContext::~EglContext() {
  EGLDisplay d = static_cast<EGLDisplay>(display_);
  eglBindAPI(EGL_OPENGL_API);
  if (eglGetCurrentContext() == static_cast<EGLContext>(context_))
    eglMakeCurrent(d, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(d, static_cast<EGLContext>(context_));
  // The display stays initialised (see acquire_display's comment).
}

void EglContext::make_current() {
  // The bound client API is per thread; the current context is looked up per API.
  eglBindAPI(EGL_OPENGL_API);
  if (eglGetCurrentContext() == static_cast<EGLContext>(context_)) return;
  if (!eglMakeCurrent(static_cast<EGLDisplay>(display_), EGL_NO_SURFACE, EGL_NO_SURFACE,
                      static_cast<EGLContext>(context_)))
    throw RenderError("EGL: eglMakeCurrent failed (" + egl_error_name(eglGetError()) +
                      "); is this renderer's context current on another thread?");
}

void EglContext::release() {
  eglBindAPI(EGL_OPENGL_API);
  if (eglGetCurrentContext() == static_cast<EGLContext>(context_))
    eglMakeCurrent(static_cast<EGLDisplay>(display_), EGL_NO_SURFACE, EGL_NO_SURFACE,
                   EGL_NO_CONTEXT);
}

}  // namespace shelfcross::render
