#include "relief/base/module.h"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <vector>

#include <fmt/format.h>

namespace relief {

namespace {

namespace fs = std::filesystem;

std::vector<fs::path> candidates(const ModuleLocation& location) {
  std::vector<fs::path> paths;
  if (const char* env = std::getenv(location.env_variable.c_str()); env && *env) {
    paths.emplace_back(env);
  }
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    paths.push_back(exe.parent_path().parent_path() / RELIEF_MODULE_INSTALL_SUBDIR /
                    fs::path(location.build_path).filename());
  }
  paths.emplace_back(location.build_path);
  return paths;
}

}  // namespace

Result<void*> load_module_symbol(const ModuleLocation& location, const std::string& symbol,
                                 SymbolScope scope) {
  std::string tried;
  for (const fs::path& path : candidates(location)) {
    std::error_code ec;
    if (!fs::exists(path, ec)) {
      tried += (tried.empty() ? "" : ", ") + path.string();
      continue;
    }
    const int flags = RTLD_NOW | (scope == SymbolScope::global ? RTLD_GLOBAL : RTLD_LOCAL);
    void* module = dlopen(path.c_str(), flags);  // never closed: kept for the process's life
    if (!module) {
      return fail(fmt::format("{}: cannot load {}: {}", location.what, path.string(), dlerror()));
    }
    void* address = dlsym(module, symbol.c_str());
    if (!address)
      return fail(fmt::format("{}: {} has no {}", location.what, path.string(), symbol));
    return address;
  }
  return fail(fmt::format("{}: the {} is not installed (looked for {})", location.what,
                          location.description, tried));
}

}  // namespace relief
