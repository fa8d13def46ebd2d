#include "source.h"

#include <cpl_conv.h>
#include <gdal_alg.h>
#include <ogr_srs_api.h>

#include <cmath>

#include <fmt/format.h>

#include "gdal_env.h"

namespace relief::ingest {
namespace {

bool is_complex(GDALDataType t) {
  return GDALDataTypeIsComplex(t) != 0;
}

std::string authority_name(OGRSpatialReferenceH srs, const std::string& wkt) {
  OSRAutoIdentifyEPSG(srs);
  const char* name = OSRGetAuthorityName(srs, nullptr);
  const char* code = OSRGetAuthorityCode(srs, nullptr);
  if (name && code) return fmt::format("{}:{}", name, code);
  return wkt;
}

std::string mosaic_key_of(GDALDatasetH ds) {
  std::string key;
  for (int b = 1; b <= GDALGetRasterCount(ds); ++b) {
    GDALRasterBandH band = GDALGetRasterBand(ds, b);
    key += fmt::format("{}:{}:{};", GDALGetDataTypeName(GDALGetRasterDataType(band)),
                       static_cast<int>(GDALGetRasterColorInterpretation(band)),
                       GDALGetRasterColorTable(band) != nullptr);
  }
  return key;
}

struct SrsDeleter {
  void operator()(OGRSpatialReferenceH h) const { OSRDestroySpatialReference(h); }
};

std::string wgs84_wkt() {
  OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
  std::unique_ptr<void, SrsDeleter> guard(srs);
  OSRImportFromEPSG(srs, 4326);
  char* out = nullptr;
  OSRExportToWkt(srs, &out);
  std::string wkt = out;
  CPLFree(out);
  return wkt;
}

// A north-up grid without a CRS whose extent can only be longitudes and
// latitudes (within -180..360 and -90..90, give or take a sample: NetCDF and
// GRIB grids are often gridline-registered, their outer samples centred on
// the poles) is taken as WGS84 geographic.
bool looks_geographic(const double* gt, int width, int height) {
  if (gt[2] != 0 || gt[4] != 0 || !(gt[1] > 0) || !(gt[5] < 0)) return false;
  const double west = gt[0], east = gt[0] + width * gt[1];
  const double north = gt[3], south = gt[3] + height * gt[5];
  return west >= -180 - gt[1] && east <= 360 + gt[1] && north <= 90 - gt[5] &&
         south >= -90 + gt[5] && east - west <= 360 + 2 * gt[1];
}

std::string xml_escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// A global geographic grid in longitudes 0..360, as a VRT whose columns from
// 180 degrees east on come first, shifted by -360: the same samples in
// -180..180, where tiles look for them.
std::string wrapped_vrt(const Source& s, GDALDatasetH ds, const double* gt) {
  const int split = static_cast<int>(std::ceil((180.0 - gt[0]) / gt[1] - 0.5));
  GDALRasterBandH band = GDALGetRasterBand(ds, 1);
  int has_nodata = 0;
  const double nodata = GDALGetRasterNoDataValue(band, &has_nodata);
  const std::string file = xml_escape(s.path);
  auto part = [&](int src_x, int width, int dst_x) {
    return fmt::format(
        "<SimpleSource><SourceFilename relativeToVRT=\"0\">{}</SourceFilename>"
        "<SourceBand>1</SourceBand><SrcRect xOff=\"{}\" yOff=\"0\" xSize=\"{}\" ySize=\"{}\"/>"
        "<DstRect xOff=\"{}\" yOff=\"0\" xSize=\"{}\" ySize=\"{}\"/></SimpleSource>",
        file, src_x, width, s.height, dst_x, width, s.height);
  };
  return fmt::format(
      "<VRTDataset rasterXSize=\"{}\" rasterYSize=\"{}\"><SRS>{}</SRS>"
      "<GeoTransform>{:.17g},{:.17g},0,{:.17g},0,{:.17g}</GeoTransform>"
      "<VRTRasterBand dataType=\"{}\" band=\"1\">{}{}{}</VRTRasterBand></VRTDataset>",
      s.width, s.height, xml_escape(s.crs_wkt), gt[0] + split * gt[1] - 360, gt[1], gt[3], gt[5],
      s.data_type,
      has_nodata ? fmt::format("<NoDataValue>{:.17g}</NoDataValue>", nodata) : std::string(),
      part(split, s.width - split, 0), part(0, split, s.width - split));
}

}  // namespace

Result<Source> describe_source(const std::string& path, tiles::DatasetKind kind,
                               const std::optional<std::string>& src_crs) {
  Dataset ds = open_raster(path);
  if (!ds) return fail(fmt::format("{}: {}", path, gdal_error("not a raster GDAL can read")));
  Source s;
  s.path = path;
  s.width = GDALGetRasterXSize(ds.get());
  s.height = GDALGetRasterYSize(ds.get());
  const int bands = GDALGetRasterCount(ds.get());
  if (bands == 0 || s.width == 0 || s.height == 0) {
    return fail(fmt::format("{}: has no raster bands", path));
  }
  const GDALDataType type = GDALGetRasterDataType(GDALGetRasterBand(ds.get(), 1));
  s.data_type = GDALGetDataTypeName(type);
  s.sample_bytes = GDALGetDataTypeSizeBytes(type);
  int block_width = 0;
  GDALGetBlockSize(GDALGetRasterBand(ds.get(), 1), &block_width, &s.block_height);
  s.mosaic_key = mosaic_key_of(ds.get());
  if (is_complex(type)) {
    return fail(
        fmt::format("{}: unsupported data type {} (complex samples; convert to amplitude first)",
                    path, s.data_type));
  }
  const GDALColorInterp last = GDALGetRasterColorInterpretation(GDALGetRasterBand(ds.get(), bands));
  s.has_alpha = bands > 1 && last == GCI_AlphaBand;
  s.colour_bands = bands - (s.has_alpha ? 1 : 0);
  if (kind == tiles::DatasetKind::Imagery) {
    if (type != GDT_Byte) {
      return fail(fmt::format("{}: unsupported data type {} for imagery (8-bit bands needed)", path,
                              s.data_type));
    }
    if (s.colour_bands != 1 && s.colour_bands != 3) {
      return fail(fmt::format("{}: has {} colour bands; imagery needs 1 (grey) or 3 (RGB)", path,
                              s.colour_bands));
    }
  } else if (s.colour_bands != 1) {
    return fail(fmt::format("{}: has {} bands; {} data needs exactly one", path, bands,
                            tiles::to_string(kind)));
  }

  // Georeferencing: a geotransform (rotated ones included) or GCPs, and a CRS.
  double gt[6];
  const bool has_gt = GDALGetGeoTransform(ds.get(), gt) == CE_None;
  const bool has_gcps = GDALGetGCPCount(ds.get()) > 0;
  if (!has_gt && !has_gcps) {
    return fail(fmt::format("{}: has no georeferencing (no geotransform or GCPs)", path));
  }
  s.north_up = has_gt && gt[2] == 0 && gt[4] == 0;
  const char* wkt = has_gt ? GDALGetProjectionRef(ds.get()) : GDALGetGCPProjection(ds.get());
  s.crs_wkt = wkt ? wkt : "";
  if (src_crs) {
    OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
    std::unique_ptr<void, SrsDeleter> guard(srs);
    if (OSRSetFromUserInput(srs, src_crs->c_str()) != OGRERR_NONE) {
      return fail(fmt::format("--src-crs: '{}' is not a coordinate reference system", *src_crs));
    }
    char* out = nullptr;
    OSRExportToWkt(srs, &out);
    s.crs_wkt = out;
    CPLFree(out);
  }
  if (s.crs_wkt.empty() && has_gt && looks_geographic(gt, s.width, s.height)) {
    s.crs_wkt = wgs84_wkt();
    s.crs_assumed = true;
  }
  if (s.crs_wkt.empty()) {
    return fail(
        fmt::format("{}: has a geotransform but no coordinate reference system "
                    "(pass --src-crs, e.g. --src-crs EPSG:4326)",
                    path));
  }
  {
    OGRSpatialReferenceH srs = OSRNewSpatialReference(s.crs_wkt.c_str());
    std::unique_ptr<void, SrsDeleter> guard(srs);
    s.crs_name = srs ? authority_name(srs, s.crs_wkt) : s.crs_wkt;
    if (s.crs_assumed) s.crs_name += " (assumed: no CRS, geographic extent)";
    // Longitudes 0..360 around the whole globe: rotated into -180..180.
    if (srs && OSRIsGeographic(srs) && s.north_up && s.colour_bands == 1 && !s.has_alpha &&
        gt[0] + s.width * gt[1] > 180 + gt[1] && s.width * gt[1] >= 360 - 1.5 * gt[1]) {
      s.wrapped = wrapped_vrt(s, ds.get(), gt);
    }
  }

  // Footprint and resolution in WGS84 geographic coordinates.
  OGRSpatialReferenceH wgs84 = OSRNewSpatialReference(nullptr);
  std::unique_ptr<void, SrsDeleter> wgs84_guard(wgs84);
  OSRImportFromEPSG(wgs84, 4326);
  OSRSetAxisMappingStrategy(wgs84, OAMS_TRADITIONAL_GIS_ORDER);
  char* dst_wkt = nullptr;
  OSRExportToWkt(wgs84, &dst_wkt);
  const char* options[] = {nullptr, nullptr, nullptr};
  const std::string src_opt = "SRC_SRS=" + s.crs_wkt;
  const std::string dst_opt = std::string("DST_SRS=") + dst_wkt;
  CPLFree(dst_wkt);
  options[0] = src_opt.c_str();
  options[1] = dst_opt.c_str();
  Dataset wrapped = s.wrapped.empty() ? Dataset() : open_raster(s.wrapped);
  if (!s.wrapped.empty() && !wrapped) {
    return fail(fmt::format("{}: cannot wrap longitudes 0..360: {}", path, gdal_error("VRT")));
  }
  GDALDatasetH placed = wrapped ? wrapped.get() : ds.get();
  void* transformer =
      GDALCreateGenImgProjTransformer2(placed, nullptr, const_cast<char**>(options));
  if (!transformer) {
    return fail(
        fmt::format("{}: cannot transform to WGS84: {}", path, gdal_error("unknown error")));
  }
  double out_gt[6];
  int px = 0, py = 0;
  double extent[4];
  const CPLErr err = GDALSuggestedWarpOutput2(placed, GDALGenImgProjTransform, transformer, out_gt,
                                              &px, &py, extent, 0);
  GDALDestroyGenImgProjTransformer(transformer);
  if (err != CE_None) {
    return fail(fmt::format("{}: cannot compute its WGS84 footprint: {}", path,
                            gdal_error("unknown error")));
  }
  s.box = {extent[0], extent[1], extent[2], extent[3]};
  s.spacing_deg = std::min(std::abs(out_gt[1]), std::abs(out_gt[5]));
  // Gridline-registered grids reach half a sample past the poles (a little
  // more in GDAL's footprint).
  const double pole = 90.0001 + s.spacing_deg;
  if (!(s.spacing_deg > 0) || s.box.south < -pole || s.box.north > pole ||
      s.box.west >= s.box.east) {
    return fail(fmt::format("{}: georeferencing gives an impossible WGS84 footprint", path));
  }
  s.box.south = std::max(s.box.south, -90.0);
  s.box.north = std::min(s.box.north, 90.0);
  return s;
}

Status check_compatible(const std::vector<Source>& sources) {
  for (const auto& s : sources) {
    if (s.colour_bands != sources.front().colour_bands) {
      return fail(fmt::format("{}: has {} colour bands but {} has {}; inputs must match", s.path,
                              s.colour_bands, sources.front().path, sources.front().colour_bands));
    }
  }
  return {};
}

tiles::SourceInfo to_source_info(const Source& s) {
  return {s.path,     s.crs_name, s.width, s.height, s.colour_bands + (s.has_alpha ? 1 : 0),
          s.data_type};
}

}  // namespace relief::ingest
