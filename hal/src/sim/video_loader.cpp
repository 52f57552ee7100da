// decode_video_gray() for builds with FFmpeg: opens the video plugin (video_plugin.hpp) the
// first time a video is replayed. The plugin is looked for in EPIPOLE_VIDEO_PLUGIN (a path),
// then in ../lib/epipole/ beside the running program: /usr/bin -> /usr/lib/epipole when
// installed, build/<preset>/<folder> -> build/<preset>/lib/epipole in a build tree.
#include <dlfcn.h>
#include <unistd.h>

#include <array>
#include <cstdlib>
#include <mutex>
#include <string>

#include "epipole/core/error.hpp"
#include "video_decoder.hpp"
#include "video_plugin.hpp"

namespace epipole::hal {
namespace {

constexpr const char* kPluginName = "libepipole_video.so";

std::filesystem::path program_folder() {
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path() : self.parent_path();
}

struct Plugin {
  EpipoleVideoDecode decode = nullptr;
  std::string error;  // why it could not be opened
};

// The plugin named by EPIPOLE_VIDEO_PLUGIN, else the one beside the program.
std::filesystem::path plugin_path() {
  if (const char* path = std::getenv("EPIPOLE_VIDEO_PLUGIN"); path != nullptr && *path != '\0') {
    return path;
  }
  return program_folder() / ".." / "lib" / "epipole" / kPluginName;
}

Plugin open_plugin() {
  const std::filesystem::path path = plugin_path();
  void* handle = ::dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) return {nullptr, ::dlerror()};
  void* entry = ::dlsym(handle, EPIPOLE_VIDEO_PLUGIN_ENTRY);
  if (entry == nullptr) {
    ::dlclose(handle);
    return {nullptr, cat(path.string(), ": no ", EPIPOLE_VIDEO_PLUGIN_ENTRY)};
  }
  return {reinterpret_cast<EpipoleVideoDecode>(entry), {}};
}

const Plugin& plugin() {
  static const Plugin loaded = open_plugin();
  return loaded;
}

}  // namespace

int decode_video_gray(const std::filesystem::path& file, int limit,
                      const std::function<void(GrayView)>& frame) {
  const Plugin& p = plugin();
  if (p.decode == nullptr) {
    throw Error(cat(file.string(), ": cannot read videos: the video plugin ", kPluginName,
                    " did not load (", p.error, "; EPIPOLE_VIDEO_PLUGIN may name it)"));
  }
  std::array<char, 512> error{};
  const auto call = [](void* context, const GrayView* view) {
    (*static_cast<const std::function<void(GrayView)>*>(context))(*view);
  };
  const int n =
      p.decode(file.c_str(), limit, call, const_cast<void*>(static_cast<const void*>(&frame)),
               error.data(), error.size());
  if (n < 0) throw Error(error.data());
  return n;
}

}  // namespace epipole::hal
