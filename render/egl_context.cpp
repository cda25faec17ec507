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
// never called. Why: with Mesa 22.3 (egl_dri2), terminating the display's last
// user destroys the screen and dlcloses the driver, swrast_dri.so with LLVM, and the next
// renderer's eglInitialize maps it again: a thread still exiting or a pointer kept across the
// unload would run code that is gone, and LeakSanitizer reported the unloaded driver's state
// as leaked (19 tests under the debug preset). Cost: the driver stays loaded until exit.
// This is NOT the cause of the general protection fault in swrast_dri.so seen in campaigns,
// as first thought. The kernel's line, "general protection fault ip:...00dc ...
// in swrast_dri.so[6e00dc,<base>+1049000]", gives the file offset first: 0x6e00dc, the same
// in both crashes logged on the build machine (11:44 and 13:05 UTC on 2026-11-24, the second
// 14 minutes after this change was committed; which code that process ran is not known). It is
// an instruction boundary, a load (movslq 0x100(%rcx),%rdx) in a loop over a list of 32-pointer
// blocks with a count at 0x100 and a next pointer at 0x108, called only from a function that
// checks a setup's framebuffer and then each of its active scenes and returns 3: by that
// layout, llvmpipe's lp_scene_is_resource_referenced() from lp_setup_is_resource_referenced()
// (inferred from the layout: Debian's driver has no symbols). A general protection fault on a
// load is a non-canonical address: the scene's resource list read while it is being reset or
// freed, a race inside llvmpipe between the context's thread (mapping a resource, as reading
// pixels back does) and llvmpipe's rasteriser threads. Not reproduced: both stress tests of
// render/test/renderer_threads_test.cpp repeated in a loop (release build, then ASan) never
// failed, and helgrind (valgrind 3.19) did not finish one of them in 15 minutes; its reports
// were all inside Mesa without symbols, several on the display's second word, likely a lock
// built on a futex that it cannot see. Campaign runs now live in worker processes, so such
// a crash costs one run, recorded `crashed`. And a campaign's worker
// processes set LP_NUM_THREADS=0 (llvmpipe rasterises on the calling thread: no rasteriser
// threads to race with; verification/campaign/run_process.cpp), which also saves CPU time.
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
