#include "relief/base/module.h"

#include <dlfcn.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

namespace relief {
namespace {

namespace fs = std::filesystem;

constexpr const char* kVariable = "RELIEF_MODULE_TEST_PATH";

ModuleLocation location_in(const fs::path& build_path) {
  return {.what = "test",
          .description = "test module",
          .env_variable = kVariable,
          .build_path = build_path.string()};
}

// The shared library that holds cos (libm): a real module to load.
fs::path libm_path() {
  Dl_info info{};
  double (*cosine)(double) = &std::cos;
  EXPECT_NE(dladdr(reinterpret_cast<void*>(cosine), &info), 0);
  return info.dli_fname;
}

TEST(LoadModuleSymbol, FindsTheSymbolInTheBuildTreePath) {
  unsetenv(kVariable);
  auto symbol = load_module_symbol(location_in(libm_path()), "cos", SymbolScope::local);
  ASSERT_TRUE(symbol.has_value()) << symbol.error().message;
  auto cosine = reinterpret_cast<double (*)(double)>(*symbol);
  EXPECT_EQ(cosine(0.0), 1.0);
}

TEST(LoadModuleSymbol, TheEnvironmentVariableComesFirst) {
  setenv(kVariable, libm_path().c_str(), 1);
  auto symbol =
      load_module_symbol(location_in("/nonexistent/module.so"), "cos", SymbolScope::global);
  unsetenv(kVariable);
  EXPECT_TRUE(symbol.has_value());
}

TEST(LoadModuleSymbol, AMissingModuleNamesEveryPathTried) {
  unsetenv(kVariable);
  auto symbol =
      load_module_symbol(location_in("/nonexistent/module.so"), "cos", SymbolScope::local);
  ASSERT_FALSE(symbol.has_value());
  EXPECT_NE(symbol.error().message.find("test: the test module is not installed"),
            std::string::npos);
  EXPECT_NE(symbol.error().message.find("/nonexistent/module.so"), std::string::npos);
  EXPECT_NE(symbol.error().message.find("relief/module.so"), std::string::npos);  // installed
}

TEST(LoadModuleSymbol, AMissingSymbolOrAFileThatIsNoLibraryIsAnError) {
  unsetenv(kVariable);
  auto symbol =
      load_module_symbol(location_in(libm_path()), "relief_no_such_symbol", SymbolScope::local);
  ASSERT_FALSE(symbol.has_value());
  EXPECT_NE(symbol.error().message.find("has no relief_no_such_symbol"), std::string::npos);

  const fs::path text = fs::temp_directory_path() / "relief-module-test-not-a-library.so";
  std::ofstream(text) << "not a library\n";
  auto bad = load_module_symbol(location_in(text), "cos", SymbolScope::local);
  fs::remove(text);
  ASSERT_FALSE(bad.has_value());
  EXPECT_NE(bad.error().message.find("test: cannot load " + text.string()), std::string::npos);
}

}  // namespace
}  // namespace relief
