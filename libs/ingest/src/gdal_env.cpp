#include "gdal_env.h"

#include <cpl_conv.h>
#include <cpl_error.h>

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <mutex>

namespace relief::ingest {

void init_gdal() {
  static std::once_flag once;
  std::call_once(once, [] {
    GDALAllRegister();
    CPLSetErrorHandler(CPLQuietErrorHandler);
    // Never write .aux.xml sidecars next to the user's inputs.
    CPLSetConfigOption("GDAL_PAM_ENABLED", "NO");
  });
}

std::string gdal_error(const std::string& fallback) {
  const char* msg = CPLGetLastErrorMsg();
  std::string text = (msg && *msg) ? msg : fallback;
  CPLErrorReset();
  // One line per error: GDAL messages sometimes span several.
  for (char& c : text) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  return text;
}

Dataset open_raster(const std::string& path) {
  init_gdal();
  CPLErrorReset();
  return Dataset(GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY | GDAL_OF_VERBOSE_ERROR,
                            nullptr, nullptr, nullptr));
}

std::optional<std::string> finish_atomic_write(Dataset& out, const std::string& tmp,
                                               const std::string& final_path) {
  CPLErrorReset();
  GDALClose(out.release());
  if (CPLGetLastErrorType() >= CE_Failure) {
    ::unlink(tmp.c_str());
    return final_path + ": write failed: " + gdal_error("GTiff");
  }
  if (::rename(tmp.c_str(), final_path.c_str()) != 0) {
    const std::string reason = std::strerror(errno);
    ::unlink(tmp.c_str());
    return final_path + ": cannot rename into place: " + reason;
  }
  return std::nullopt;
}

}  // namespace relief::ingest
