#include "gdal_env.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>

#include <cpl_conv.h>
#include <cpl_error.h>

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <mutex>

#include "relief/base/file_io.h"

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

namespace {

// What GDAL would read for `path`, as a file of this file system: the path
// itself, or for a /vsizip/-style path the nearest part of it that exists
// ("/vsizip/a/b.zip/c.hgt": a/b.zip).
std::optional<std::filesystem::path> local_file_of(const std::string& path) {
  std::filesystem::path p = path;
  if (path.starts_with("/vsi")) {
    const size_t slash = path.find('/', 1);
    if (slash == std::string::npos) return std::nullopt;
    p = path.substr(slash + 1);
  }
  for (; !p.empty() && p != p.root_path(); p = p.parent_path()) {
    struct stat st {};
    if (::stat(p.c_str(), &st) == 0) return p;
  }
  return std::nullopt;
}

}  // namespace

Dataset open_raster(const std::string& path) {
  init_gdal();
  CPLErrorReset();
  // GDAL would wait on a FIFO for a writer forever and read a device without
  // end: only regular files (and directories, which some formats are) open.
  std::error_code ec;
  if (const auto file = local_file_of(path); file && !std::filesystem::is_directory(*file, ec)) {
    if (auto regular = check_regular_file(*file); !regular) {
      // Callers put `path` before the message: name the file only if it is another.
      std::string message = regular.error().message;
      if (file->string() == path) message.erase(0, path.size() + 2);
      CPLError(CE_Failure, CPLE_OpenFailed, "%s", message.c_str());
      return nullptr;
    }
  }
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
  if (auto replaceable = check_replaceable(final_path); !replaceable) {
    ::unlink(tmp.c_str());
    return replaceable.error().message;
  }
  if (::rename(tmp.c_str(), final_path.c_str()) != 0) {
    const std::string reason = std::strerror(errno);
    ::unlink(tmp.c_str());
    return final_path + ": cannot rename into place: " + reason;
  }
  return std::nullopt;
}

Result<SingleBand> open_single_band(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    return fail(path + ": is a directory, not a raster");
  }
  Dataset ds = open_raster(path);
  if (!ds) return fail(path + ": " + gdal_error("not a raster GDAL can read"));
  if (const int bands = GDALGetRasterCount(ds.get()); bands != 1) {
    return fail(path + ": has " + std::to_string(bands) + " bands; expected one");
  }
  GDALRasterBandH band = GDALGetRasterBand(ds.get(), 1);
  if (GDALDataTypeIsComplex(GDALGetRasterDataType(band))) {
    return fail(path + ": unsupported data type " +
                GDALGetDataTypeName(GDALGetRasterDataType(band)) +
                " (complex; convert to amplitude first)");
  }
  return SingleBand{std::move(ds), band};
}

std::optional<std::string> read_padded(GDALRasterBandH band, int x0, int y0, int w, int h,
                                       int margin, std::vector<float>& out,
                                       const std::string& name) {
  const int width = GDALGetRasterBandXSize(band), height = GDALGetRasterBandYSize(band);
  const int padded_w = w + 2 * margin, padded_h = h + 2 * margin;
  out.assign(static_cast<size_t>(padded_w) * padded_h, std::numeric_limits<float>::quiet_NaN());
  const int rx0 = std::max(0, x0 - margin), rx1 = std::min(width, x0 + w + margin);
  const int ry0 = std::max(0, y0 - margin), ry1 = std::min(height, y0 + h + margin);
  if (rx1 <= rx0 || ry1 <= ry0) return std::nullopt;
  float* dst =
      out.data() + static_cast<size_t>(ry0 - (y0 - margin)) * padded_w + (rx0 - (x0 - margin));
  if (GDALRasterIO(band, GF_Read, rx0, ry0, rx1 - rx0, ry1 - ry0, dst, rx1 - rx0, ry1 - ry0,
                   GDT_Float32, 0, static_cast<GSpacing>(padded_w) * 4) != CE_None) {
    return name + ": read failed: " + gdal_error("GDAL");
  }
  // A sample that is not finite (an infinite amplitude or height) is no
  // measurement: nodata, as the band's own nodata value is.
  int has_nodata = 0;
  const double nodata = GDALGetRasterNoDataValue(band, &has_nodata);
  const float nd =
      has_nodata ? static_cast<float>(nodata) : std::numeric_limits<float>::quiet_NaN();
  for (float& v : out) {
    if (v == nd || std::isinf(v)) v = std::numeric_limits<float>::quiet_NaN();
  }
  return std::nullopt;
}

}  // namespace relief::ingest
