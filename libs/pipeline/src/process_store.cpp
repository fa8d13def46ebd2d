#include "relief/pipeline/process_store.h"

#include <chrono>
#include <cmath>
#include <mutex>

#include <fmt/format.h>

#include "relief/base/first_error.h"
#include "relief/process/operators.h"
#include "store_output.h"
#include "tile_reader.h"

namespace relief::pipeline {
namespace {

std::string units_after(const process::OperatorSpec& op, const std::string& units) {
  if (op.needs_global_stats) return "grey level";
  if (op.name == "amplitude-to-db") return "dB";
  if (op.name == "amplitude-to-intensity") return "intensity";
  if (op.name.ends_with("-to-amplitude")) return "amplitude";
  return units;
}

Status check_input(const tiles::Manifest& m, const process::OperatorSpec& op,
                   const std::string& name) {
  if (m.sample_type != tiles::SampleType::Float32) {
    return fail(fmt::format("{}: holds {} imagery; operators work on single-band stores", name,
                            tiles::to_string(m.kind)));
  }
  if (op.sar_only && m.kind != tiles::DatasetKind::Sar) {
    return fail(fmt::format("{}: operator {} expects {}, but the store holds {} data", name,
                            op.name, op.input, tiles::to_string(m.kind)));
  }
  if (m.stats.valid_count == 0) return fail(fmt::format("{}: holds no valid samples", name));
  return {};
}

}  // namespace

Result<ProcessStoreReport> process_store(const ProcessStoreOptions& o, Executor& executor,
                                         Progress& progress) {
  const auto start = std::chrono::steady_clock::now();
  const process::OperatorSpec* op = process::find_operator(o.op);
  if (!op) return fail(fmt::format("--op: unknown operator '{}' (see --list)", o.op));
  const process::Params params = RELIEF_TRY(process::parse_params(*op, o.params));
  const tiles::Store input = RELIEF_TRY(tiles::Store::open(o.input));
  const tiles::Manifest& m = input.manifest();
  RELIEF_CHECK(check_input(m, *op, o.input.string()));
  const process::GlobalStats stats{m.stats.min, m.stats.max, m.stats.mean, m.stats.stddev};
  const int border = m.border;
  const geo::TileGrid& grid = input.grid();

  StoreOutput output = RELIEF_TRY(StoreOutput::create(o.output, m.min_level, m.max_level));
  TileReader reader(input, o.memory_budget);
  tiles::CodecOptions codec;  // lossless: derived values have no meaningful LERC error bound
  uint64_t total = 0;
  for (int l = m.min_level; l <= m.max_level; ++l) total += input.index(l).size();
  progress.begin(fmt::format("process {}", op->name), total);
  for (int level = m.min_level; level <= m.max_level; ++level) {
    // Level `level` is 2^(max - level) times coarser than the finest.
    const double factor = std::ldexp(1.0, m.max_level - level);
    const process::Params level_params = process::scale_params(*op, params, factor);
    const int margin = process::margin_of(*op, level_params);
    if (border + margin > std::min(grid.width(), grid.height())) {
      return fail(fmt::format("{}: margin {} exceeds a tile", op->name, margin));
    }
    const auto& entries = input.index(level).entries();
    FirstError error;
    executor.parallel_for(entries.size(), [&](size_t i) {
      if (error.failed()) return;
      const geo::TileKey key = entries[i].key;
      auto window = reader.window(key, border + margin);
      if (!window) return error.set(window.error());
      const int w = window->width(), h = window->height();
      const int64_t x0 = int64_t{key.x} * grid.width() - border - margin;
      const int64_t y0 = int64_t{key.y} * grid.height() - border - margin;
      const process::ConstView in{window->f32().data(), w, h, w, x0, y0};
      tiles::Raster result(tiles::SampleType::Float32, 1, w - 2 * margin, h - 2 * margin);
      const process::MutView out{result.f32().data(), result.width(), result.height(),
                                 result.width(),      x0 + margin,    y0 + margin};
      InlineExecutor inline_executor;
      auto st = process::run_operator(*op, level_params, in, out, inline_executor, &stats);
      if (!st) return error.set(st.error());
      if (result.stats(border, border, grid.width(), grid.height()).valid_count > 0) {
        if (auto w_st = output.write(key, result, border, codec); !w_st) {
          return error.set(w_st.error());
        }
      }
      progress.advance();
    });
    RELIEF_CHECK(error.status());
  }
  progress.end();
  tiles::Manifest out_manifest = m;
  out_manifest.codec = codec;
  out_manifest.units = units_after(*op, m.units);
  std::string described = o.op;
  for (const auto& p : o.params) described += " " + p;
  out_manifest.created_by = fmt::format("relief process --op {} ({})", described, o.input.string());
  const uint64_t tiles_written = output.tiles_written();
  RELIEF_CHECK(output.finish(std::move(out_manifest), executor, progress));
  return ProcessStoreReport{
      tiles_written, m.max_level - m.min_level + 1,
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()};
}

}  // namespace relief::pipeline
