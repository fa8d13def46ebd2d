#include "gdal_reference.h"

#include <cpl_conv.h>
#include <gdal.h>
#include <gdal_utils.h>
#include <ogr_srs_api.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace relief::testing {

namespace {
void init() {
  static bool done = false;
  if (!done) {
    GDALAllRegister();
    done = true;
  }
}
}  // namespace

SourceGrid read_source(const std::string& path, int band) {
  init();
  GDALDatasetH ds = GDALOpen(path.c_str(), GA_ReadOnly);
  if (!ds) throw std::runtime_error("cannot open " + path);
  SourceGrid g;
  g.width = GDALGetRasterXSize(ds);
  g.height = GDALGetRasterYSize(ds);
  GDALGetGeoTransform(ds, g.gt);
  GDALRasterBandH b = GDALGetRasterBand(ds, band);
  int has = 0;
  g.nodata = GDALGetRasterNoDataValue(b, &has);
  g.has_nodata = has != 0;
  g.values.resize(static_cast<size_t>(g.width) * g.height);
  if (GDALRasterIO(b, GF_Read, 0, 0, g.width, g.height, g.values.data(), g.width, g.height,
                   GDT_Float64, 0, 0) != CE_None) {
    throw std::runtime_error("cannot read " + path);
  }
  GDALClose(ds);
  return g;
}

bool bilinear(const SourceGrid& g, double lon, double lat, double& value) {
  const double u = (lon - g.gt[0]) / g.gt[1] - 0.5;
  const double v = (lat - g.gt[3]) / g.gt[5] - 0.5;
  const int i = static_cast<int>(std::floor(u)), j = static_cast<int>(std::floor(v));
  if (i < 0 || j < 0 || i + 1 >= g.width || j + 1 >= g.height) return false;
  for (int dj = 0; dj < 2; ++dj) {
    for (int di = 0; di < 2; ++di) {
      if (!g.valid(i + di, j + dj)) return false;
    }
  }
  const double fu = u - i, fv = v - j;
  value = (1 - fv) * ((1 - fu) * g.at(i, j) + fu * g.at(i + 1, j)) +
          fv * ((1 - fu) * g.at(i, j + 1) + fu * g.at(i + 1, j + 1));
  return true;
}

namespace {
Warped read_all(GDALDatasetH ds) {
  Warped w;
  w.width = GDALGetRasterXSize(ds);
  w.height = GDALGetRasterYSize(ds);
  w.bands = GDALGetRasterCount(ds);
  GDALGetGeoTransform(ds, w.gt);
  w.values.resize(static_cast<size_t>(w.width) * w.height * w.bands);
  if (GDALDatasetRasterIO(ds, GF_Read, 0, 0, w.width, w.height, w.values.data(), w.width, w.height,
                          GDT_Float64, w.bands, nullptr, 0, 0, 0) != CE_None) {
    throw std::runtime_error("cannot read warped raster");
  }
  return w;
}
}  // namespace

Warped read_warped(const std::string& path) {
  init();
  GDALDatasetH ds = GDALOpen(path.c_str(), GA_ReadOnly);
  if (!ds) throw std::runtime_error("cannot open " + path);
  Warped w = read_all(ds);
  GDALClose(ds);
  return w;
}

void build_vrt(const std::vector<std::string>& inputs, const std::string& path) {
  init();
  std::vector<const char*> names;
  for (const auto& in : inputs) names.push_back(in.c_str());
  int usage = 0;
  GDALDatasetH vrt = GDALBuildVRT(path.c_str(), static_cast<int>(names.size()), nullptr,
                                  names.data(), nullptr, &usage);
  if (!vrt) throw std::runtime_error("gdalbuildvrt failed");
  GDALClose(vrt);
}

Warped gdalwarp_like(const std::vector<std::string>& inputs, const Warped& like,
                     const std::string& resampling, bool alpha, double error_threshold,
                     const std::vector<std::string>& warp_options) {
  init();
  std::vector<GDALDatasetH> srcs;
  for (const auto& in : inputs) srcs.push_back(GDALOpen(in.c_str(), GA_ReadOnly));
  const double west = like.gt[0], north = like.gt[3];
  const double east = west + like.width * like.gt[1], south = north + like.height * like.gt[5];
  auto exact = [](double v) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return std::string(buf);
  };
  const std::vector<std::string> args_s = {"-of",
                                           "MEM",
                                           "-t_srs",
                                           "EPSG:4326",
                                           "-te",
                                           exact(west),
                                           exact(south),
                                           exact(east),
                                           exact(north),
                                           "-ts",
                                           std::to_string(like.width),
                                           std::to_string(like.height),
                                           "-r",
                                           resampling,
                                           "-ot",
                                           alpha ? "Byte" : "Float32",
                                           "-et",
                                           exact(error_threshold)};
  std::vector<std::string> all = args_s;
  for (const auto& wo : warp_options) {
    all.push_back("-wo");
    all.push_back(wo);
  }
  if (alpha)
    all.push_back("-dstalpha");
  else {
    all.push_back("-dstnodata");
    all.push_back("nan");
  }
  std::vector<char*> argv;
  for (auto& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  GDALWarpAppOptions* opts = GDALWarpAppOptionsNew(argv.data(), nullptr);
  int usage = 0;
  GDALDatasetH out =
      GDALWarp("", nullptr, static_cast<int>(srcs.size()), srcs.data(), opts, &usage);
  GDALWarpAppOptionsFree(opts);
  if (!out) throw std::runtime_error("gdalwarp failed");
  Warped w = read_all(out);
  GDALClose(out);
  for (auto s : srcs) GDALClose(s);
  return w;
}

void write_geotiff(const std::string& path, int width, int height, const double gt[6],
                   const std::vector<float>& values, const std::string& type,
                   const std::string& srs) {
  init();
  GDALDataType t = GDALGetDataTypeByName(type.c_str());
  GDALDatasetH ds =
      GDALCreate(GDALGetDriverByName("GTiff"), path.c_str(), width, height, 1, t, nullptr);
  if (!ds) throw std::runtime_error("cannot create " + path);
  GDALSetGeoTransform(ds, const_cast<double*>(gt));
  if (!srs.empty()) {
    OGRSpatialReferenceH s = OSRNewSpatialReference(nullptr);
    OSRSetFromUserInput(s, srs.c_str());
    char* wkt = nullptr;
    OSRExportToWkt(s, &wkt);
    GDALSetProjection(ds, wkt);
    CPLFree(wkt);
    OSRDestroySpatialReference(s);
  }
  if (!GDALDataTypeIsComplex(t)) {
    if (GDALRasterIO(GDALGetRasterBand(ds, 1), GF_Write, 0, 0, width, height,
                     const_cast<float*>(values.data()), width, height, GDT_Float32, 0,
                     0) != CE_None) {
      throw std::runtime_error("cannot write " + path);
    }
  }
  GDALClose(ds);
}

}  // namespace relief::testing
