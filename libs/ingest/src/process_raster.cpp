#include "relief/ingest/process_raster.h"

#include <cpl_conv.h>
#include <gdal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

#include <fmt/format.h>

#include "gdal_env.h"
#include "relief/base/file_io.h"
#include "relief/process/operators.h"

namespace relief::ingest {

Result<ProcessRasterReport> process_raster(const ProcessRasterOptions& o, Executor& executor,
                                           Progress& progress) {
  const auto start = std::chrono::steady_clock::now();
  const process::OperatorSpec* op = process::find_operator(o.op);
  if (!op)
    return fail(fmt::format("--op: unknown operator '{}' (see relief process --list)", o.op));
  const process::Params params = RELIEF_TRY(process::parse_params(*op, o.params));
  const int margin = process::margin_of(*op, params);

  auto [in, band] = RELIEF_TRY(open_single_band(o.input));
  // 8- and 16-bit samples are small integers: no need to scan for it.
  const GDALDataType type = GDALGetRasterDataType(band);
  const std::optional<bool> small_integers =
      type == GDT_Byte || type == GDT_UInt16 || type == GDT_Int16 ? std::optional<bool>(true)
                                                                  : std::nullopt;
  const int width = GDALGetRasterXSize(in.get()), height = GDALGetRasterYSize(in.get());
  // Global operators see the statistics of the whole raster (one scan, nodata left out).
  std::optional<process::GlobalStats> stats;
  if (op->needs_global_stats) {
    process::GlobalStats g;
    CPLErrorReset();
    if (GDALComputeRasterStatistics(band, FALSE, &g.min, &g.max, &g.mean, &g.stddev, nullptr,
                                    nullptr) != CE_None) {
      return fail(fmt::format("{}: no statistics: {}", o.input,
                              gdal_error("no valid samples (nodata everywhere)")));
    }
    stats = g;
  }

  // Strips of output rows sized so input and output buffers use at most half
  // the budget (GDAL's cache takes an eighth).
  GDALSetCacheMax64(static_cast<GIntBig>(std::min<uint64_t>(o.memory_budget / 8, 16 << 20)));
  const uint64_t row_bytes = static_cast<uint64_t>(width + 2 * margin) * 4 * 2;
  // Strips of at most 256 rows keep the buffers in cache and reused; the
  // margin rows read twice cost little.
  const int strip =
      static_cast<int>(std::clamp<uint64_t>(o.memory_budget / 2 / row_bytes, 16, 256));

  static_cast<void>(remove_stale_temporaries_of(o.output));  // of killed runs
  const std::string tmp = o.output.string() + std::string(kTempMarker) + std::to_string(::getpid());
  if (o.compress != "none" && o.compress != "deflate" && o.compress != "zstd") {
    return fail(fmt::format("--compress: '{}' is not none, deflate or zstd", o.compress));
  }
  const std::string compress =
      "COMPRESS=" + (o.compress == "none" ? std::string("NONE") : o.compress);
  const char* create_options[] = {"TILED=YES", compress.c_str(),
                                  o.compress == "none" ? "PREDICTOR=1" : "PREDICTOR=3",
                                  "BIGTIFF=IF_SAFER", nullptr};
  Dataset out(GDALCreate(GDALGetDriverByName("GTiff"), tmp.c_str(), width, height, 1, GDT_Float32,
                         const_cast<char**>(create_options)));
  if (!out)
    return fail(fmt::format("{}: cannot create: {}", o.output.string(), gdal_error("GTiff")));
  double gt[6];
  if (GDALGetGeoTransform(in.get(), gt) == CE_None) GDALSetGeoTransform(out.get(), gt);
  GDALSetProjection(out.get(), GDALGetProjectionRef(in.get()));
  GDALRasterBandH out_band = GDALGetRasterBand(out.get(), 1);
  GDALSetRasterNoDataValue(out_band, std::numeric_limits<double>::quiet_NaN());
  auto discard = [&](std::string message) -> Result<ProcessRasterReport> {
    out.reset();
    ::unlink(tmp.c_str());
    return fail(std::move(message));
  };

  const int padded_width = width + 2 * margin;
  std::vector<float> input_rows, output_rows;
  progress.begin(fmt::format("{} r={}", op->name, margin), static_cast<uint64_t>(height));
  for (int y0 = 0; y0 < height; y0 += strip) {
    const int rows = std::min(strip, height - y0);
    // Input rows [y0 - margin, y0 + rows + margin); outside the image is nodata.
    if (auto error = read_padded(band, 0, y0, width, rows, margin, input_rows, o.input)) {
      return discard(*error);
    }
    output_rows.resize(static_cast<size_t>(width) * rows);
    const process::ConstView in_view{input_rows.data(), padded_width, rows + 2 * margin,
                                     padded_width,      -margin,      y0 - margin};
    const process::MutView out_view{output_rows.data(), width, rows, width, 0, y0};
    if (auto st = process::run_operator(*op, params, in_view, out_view, executor,
                                        stats ? &*stats : nullptr, small_integers);
        !st) {
      return discard(st.error().message);
    }
    if (GDALRasterIO(out_band, GF_Write, 0, y0, width, rows, output_rows.data(), width, rows,
                     GDT_Float32, 0, 0) != CE_None) {
      return discard(fmt::format("{}: write failed: {}", o.output.string(), gdal_error("GTiff")));
    }
    progress.advance(static_cast<uint64_t>(rows));
  }
  progress.end();
  if (auto error = finish_atomic_write(out, tmp, o.output.string())) return fail(*error);
  return ProcessRasterReport{
      width, height,
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()};
}

}  // namespace relief::ingest
