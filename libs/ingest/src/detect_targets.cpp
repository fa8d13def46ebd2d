#include "relief/ingest/detect_targets.h"

#include <gdal_alg.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "gdal_env.h"
#include "relief/base/file_io.h"
#include "relief/tiles/codec.h"

namespace relief::ingest {
namespace {

using nlohmann::json;

// Pixel-centre coordinates to WGS84 longitude/latitude through the raster's
// georeferencing (geotransform, GCPs or RPCs); nullopt when it has none.
class LonLat {
 public:
  explicit LonLat(GDALDatasetH ds) {
    const char* options[] = {nullptr, nullptr};
    const std::string dst = std::string("DST_SRS=") + kWgs84Wkt;
    options[0] = dst.c_str();
    CPLErrorReset();
    transformer_ = GDALCreateGenImgProjTransformer2(ds, nullptr, const_cast<char**>(options));
  }
  ~LonLat() {
    if (transformer_) GDALDestroyGenImgProjTransformer(transformer_);
  }
  LonLat(const LonLat&) = delete;
  LonLat& operator=(const LonLat&) = delete;
  std::optional<std::pair<double, double>> operator()(double x, double y) const {
    if (!transformer_) return std::nullopt;
    double px = x + 0.5, py = y + 0.5, z = 0;
    int ok = 0;
    GDALGenImgProjTransform(transformer_, FALSE, 1, &px, &py, &z, &ok);
    if (!ok) return std::nullopt;
    return std::pair{px, py};
  }

 private:
  void* transformer_ = nullptr;
};

json position(const LonLat& lonlat, int64_t x, int64_t y) {
  json p = {{"x", x}, {"y", y}};
  if (auto ll = lonlat(static_cast<double>(x), static_cast<double>(y))) {
    p["lon"] = ll->first;
    p["lat"] = ll->second;
  }
  return p;
}

std::string geojson_of(const std::vector<process::Detection>& found, const LonLat& lonlat,
                       const std::string& input) {
  json features = json::array();
  for (const auto& d : found) {
    json geometry = nullptr;
    if (auto ll = lonlat(static_cast<double>(d.x), static_cast<double>(d.y))) {
      geometry = {{"type", "Point"}, {"coordinates", {ll->first, ll->second}}};
    }
    features.push_back({{"type", "Feature"},
                        {"geometry", geometry},
                        {"properties",
                         {{"x", d.x},
                          {"y", d.y},
                          {"amplitude", d.amplitude},
                          {"side_lobe_directions_deg", {d.direction[0], d.direction[1]}},
                          {"pslr_db", std::isfinite(d.pslr_db) ? json(d.pslr_db) : json()}}}});
  }
  return json{{"type", "FeatureCollection"},
              {"source", input},
              {"directions", "degrees counter-clockwise from the image's column axis"},
              {"features", features}}
      .dump(1);
}

json analysis_json(const process::TargetAnalysis& t, const LonLat& lonlat) {
  json axes = json::array();
  for (const auto& a : t.axes) {
    json db = json::array();
    for (double v : a.db) db.push_back(std::isfinite(v) ? json(v) : json());
    axes.push_back({{"direction_deg", a.direction},
                    {"pslr_db", std::isfinite(a.pslr_db) ? json(a.pslr_db) : json()},
                    {"width_3db_samples", a.width_3db},
                    {"first_offset", -t.half_length},
                    {"db", db}});
  }
  return {{"target", position(lonlat, t.x, t.y)},
          {"amplitude", t.amplitude},
          {"pslr_db", std::isfinite(t.pslr_db) ? json(t.pslr_db) : json()},
          {"axes", axes}};
}

Status write_text(const std::filesystem::path& path, const std::string& text) {
  return write_file_atomic(path, std::as_bytes(std::span(text.data(), text.size())));
}

// The largest finite sample of the band, read a strip at a time.
Result<double> finite_maximum(GDALRasterBandH band, int width, int height, int strip,
                              const std::string& name) {
  double most = -std::numeric_limits<double>::infinity();
  std::vector<float> buffer;
  for (int y0 = 0; y0 < height; y0 += strip) {
    if (auto e = read_padded(band, 0, y0, width, std::min(strip, height - y0), 0, buffer, name)) {
      return fail(*e);
    }
    for (float v : buffer) {
      if (!std::isnan(v)) most = std::max(most, static_cast<double>(v));
    }
  }
  return most;
}

}  // namespace

Result<DetectReport> detect_targets(const DetectOptions& o, Executor& executor,
                                    Progress& progress) {
  auto [in, band] = RELIEF_TRY(open_single_band(o.input));
  double lo = 0, hi = 0, mean = 0, sd = 0;
  CPLErrorReset();
  if (GDALComputeRasterStatistics(band, FALSE, &lo, &hi, &mean, &sd, nullptr, nullptr) != CE_None ||
      !(hi > 0)) {
    return fail(fmt::format("{}: no positive amplitudes (nodata everywhere?)", o.input));
  }
  const int width = GDALGetRasterXSize(in.get()), height = GDALGetRasterYSize(in.get());
  constexpr int kStrip = 256;
  // GDAL's statistics count infinite samples, which are nodata here.
  if (!std::isfinite(hi)) hi = RELIEF_TRY(finite_maximum(band, width, height, kStrip, o.input));
  if (!(hi > 0))
    return fail(fmt::format("{}: no positive amplitudes (nodata everywhere?)", o.input));
  const int strips = (height + kStrip - 1) / kStrip;
  std::vector<std::vector<process::Detection>> per_strip(static_cast<size_t>(strips));
  std::mutex gdal_mutex;  // one dataset handle: reads are serialised
  std::optional<std::string> read_error;
  progress.begin("detect", static_cast<uint64_t>(height));
  executor.parallel_for(static_cast<size_t>(strips), [&](size_t s) {
    const int y0 = static_cast<int>(s) * kStrip, rows = std::min(kStrip, height - y0);
    const int m = process::kDetectorMargin;
    std::vector<float> buffer;
    {
      std::lock_guard lock(gdal_mutex);
      if (read_error) return;
      if (auto e = read_padded(band, 0, y0, width, rows, m, buffer, o.input)) {
        read_error = e;
        return;
      }
    }
    const process::ConstView view{buffer.data(), width + 2 * m, rows + 2 * m, width + 2 * m, -m,
                                  y0 - m};
    per_strip[s] = process::detect_point_targets(view, hi, o.detector);
    progress.advance(static_cast<uint64_t>(rows));
  });
  progress.end();
  if (read_error) return fail(*read_error);
  std::vector<process::Detection> found;
  for (auto& s : per_strip) found.insert(found.end(), s.begin(), s.end());

  const LonLat lonlat(in.get());
  DetectReport report{found.size(), hi, std::nullopt};
  if (o.analysis_json.empty() && o.analysis_png.empty()) {
    RELIEF_CHECK(write_text(o.geojson, geojson_of(found, lonlat, o.input)));
    return report;
  }

  // The target to analyse: the detection nearest the requested pixel, or the strongest.
  const process::Detection* target = nullptr;
  for (const auto& d : found) {
    if (o.analyse_at) {
      const double dist =
          std::hypot(double(d.x - o.analyse_at->first), double(d.y - o.analyse_at->second));
      if (dist <= 3 && (!target || dist < std::hypot(double(target->x - o.analyse_at->first),
                                                     double(target->y - o.analyse_at->second)))) {
        target = &d;
      }
    } else if (!target || d.amplitude > target->amplitude) {
      target = &d;
    }
  }
  if (!target) {
    return fail(o.analyse_at
                    ? fmt::format("--analyse: no target detected within 3 samples of {},{}",
                                  o.analyse_at->first, o.analyse_at->second)
                    : std::string("no target detected: nothing to analyse"));
  }
  const int r = o.half_length + 1;
  std::vector<float> window;
  if (auto e = read_padded(band, static_cast<int>(target->x), static_cast<int>(target->y), 1, 1, r,
                           window, o.input)) {
    return fail(*e);
  }
  const process::ConstView view{window.data(), 2 * r + 1,     2 * r + 1,
                                2 * r + 1,     target->x - r, target->y - r};
  report.analysis = process::analyse_point_target(view, *target, o.half_length);
  RELIEF_CHECK(write_text(o.geojson, geojson_of(found, lonlat, o.input)));
  if (!o.analysis_json.empty()) {
    RELIEF_CHECK(write_text(o.analysis_json, analysis_json(*report.analysis, lonlat).dump(1)));
  }
  if (!o.analysis_png.empty()) {
    constexpr int kW = 640, kH = 360;
    const auto pixels = process::plot_cross_sections(*report.analysis, kW, kH);
    tiles::Raster image(tiles::SampleType::UInt8, 4, kW, kH);
    std::copy(pixels.begin(), pixels.end(), image.u8().begin());
    auto png = RELIEF_TRY(tiles::encode(image, tiles::CodecOptions{tiles::Codec::Png}));
    RELIEF_CHECK(write_file_atomic(o.analysis_png, png));
  }
  return report;
}

}  // namespace relief::ingest
