#include "renderer/image/preview_writer.h"

#include <dlfcn.h>
#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <future>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

namespace farm {
namespace {

namespace fs = std::filesystem;
constexpr const char* kModuleName = "libfarm_oiio_preview.so";

std::vector<fs::path> places_to_look() {
  std::vector<fs::path> places;
  if (const char* env = std::getenv("FARM_PREVIEW_MODULE"); env != nullptr && *env != '\0') places.emplace_back(env);
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) places.push_back(self.parent_path() / kModuleName);
  const fs::path built = FARM_PREVIEW_MODULE_PATH;  // the build tree, for the tests and benchmarks
  if (std::find(places.begin(), places.end(), built) == places.end()) places.push_back(built);
  return places;
}

PreviewWriter open_module() {
  std::string tried;
  for (const fs::path& place : places_to_look()) {
    // Never closed: the previews of a long-running scheduler keep using it.
    void* handle = ::dlopen(place.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle == nullptr) {
      const char* why = ::dlerror();
      tried += "\n  " + (why != nullptr ? std::string(why) : place.string() + ": cannot open");  // names the file
      continue;
    }
    PreviewWriter writer;
    writer.can_write = reinterpret_cast<FarmPreviewCanWrite>(::dlsym(handle, "farm_preview_can_write"));
    writer.write_rgb8 = reinterpret_cast<FarmPreviewWriteRgb8>(::dlsym(handle, "farm_preview_write_rgb8"));
    if (writer.can_write != nullptr && writer.write_rgb8 != nullptr) return writer;
    tried += fmt::format("\n  {}: not a farm preview module (its functions are missing)", place.string());
  }
  throw std::runtime_error("cannot load the PNG/JPEG preview writer (" + std::string(kModuleName) +
                           ", built with farm; FARM_PREVIEW_MODULE names another place):" + tried);
}

std::mutex loading_mutex;
std::shared_future<PreviewWriter> loading;  // valid once a load has started

std::shared_future<PreviewWriter> start_or_join_loading() {
  const std::lock_guard<std::mutex> lock(loading_mutex);
  if (!loading.valid()) loading = std::async(std::launch::async, open_module).share();
  return loading;
}

}  // namespace

const PreviewWriter& preview_writer() {
  const std::shared_future<PreviewWriter> load = start_or_join_loading();
  try {
    return load.get();  // the shared state, and with it the writer, lives in `loading`
  } catch (...) {
    const std::lock_guard<std::mutex> lock(loading_mutex);
    loading = {};  // a failure is retried on the next call
    throw;
  }
}

void start_loading_preview_writer() { start_or_join_loading(); }

}  // namespace farm
