#include <cstdio>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "args.h"
#include "commands.h"
#include "open_store.h"
#include "relief/base/units.h"
#include "relief/tiles/store.h"

namespace relief::cli {

namespace {
constexpr const char* kInfoHelp = R"(usage: relief info STORE [--json]

Prints the store's manifest, the tiles and bytes per level, and the compression
ratio against the raw samples (borders included).
)";
}  // namespace

int run_info(const std::vector<std::string>& argv) {
  if (wants_help(argv)) return print_help(kInfoHelp);
  auto args = Args::parse(argv, {{"--json", "", false}}, "info");
  if (!args) return report_error(args.error().message);
  if (args->positional().size() != 1) return report_error("info: expected exactly one STORE");
  auto store = open_store(args->positional()[0]);
  if (!store) return report_error(store.error().message);
  const auto& m = store->manifest();
  const auto& g = store->grid();
  const uint64_t raw_tile = static_cast<uint64_t>(g.padded_width()) * g.padded_height() * m.bands *
                            tiles::sample_size(m.sample_type);

  nlohmann::json levels = nlohmann::json::array();
  uint64_t total_tiles = 0, total_bytes = 0;
  for (int level = m.min_level; level <= m.max_level; ++level) {
    const auto& index = store->index(level);
    levels.push_back({{"level", level},
                      {"tiles", index.size()},
                      {"bytes", index.total_bytes()},
                      {"sample_spacing_deg", g.sample_spacing(level)}});
    total_tiles += index.size();
    total_bytes += index.total_bytes();
  }
  const double ratio =
      total_bytes ? static_cast<double>(total_tiles * raw_tile) / static_cast<double>(total_bytes)
                  : 0.0;

  if (args->has("--json")) {
    nlohmann::json j;
    j["manifest"] = nlohmann::json::parse(m.to_json());
    j["levels"] = levels;
    j["total"] = {{"tiles", total_tiles},
                  {"bytes", total_bytes},
                  {"raw_bytes", total_tiles * raw_tile},
                  {"compression_ratio", ratio}};
    std::puts(j.dump(2).c_str());
    return 0;
  }
  std::string out;
  out += fmt::format("store        {}\n", store->root().string());
  out += fmt::format("kind         {} ({} x {}, units '{}', nodata {})\n", tiles::to_string(m.kind),
                     tiles::to_string(m.sample_type), m.bands, m.units, m.nodata_description());
  out += fmt::format("tiles        {} x {} samples + border {}, cell-centred\n", g.width(),
                     g.height(), g.border());
  out += fmt::format("codec        {}", tiles::to_string(m.codec.codec));
  if (m.codec.codec == tiles::Codec::Lerc) out += fmt::format(" (max error {})", m.codec.max_error);
  out += "\n";
  out += fmt::format("extent       W {:.6f}  S {:.6f}  E {:.6f}  N {:.6f}\n", m.extent.west,
                     m.extent.south, m.extent.east, m.extent.north);
  out += fmt::format(
      "statistics   min {:.3f}  max {:.3f}  mean {:.3f}  std {:.3f}  ({} valid samples)\n",
      m.stats.min, m.stats.max, m.stats.mean, m.stats.stddev, m.stats.valid_count);
  for (const auto& s : m.sources) {
    out +=
        fmt::format("source       {} ({} x {} x {} {}, {})\n", s.path, s.width, s.height, s.bands,
                    s.data_type, s.crs.size() > 40 ? s.crs.substr(0, 40) + "..." : s.crs);
  }
  out += fmt::format("created by   {}\n", m.created_by);
  out += fmt::format("\n{:>5} {:>12} {:>8} {:>12}\n", "level", "spacing", "tiles", "bytes");
  for (const auto& l : levels) {
    out += fmt::format("{:>5} {:>11.7f}° {:>8} {:>12}\n", l["level"].get<int>(),
                       l["sample_spacing_deg"].get<double>(), l["tiles"].get<uint64_t>(),
                       format_bytes(l["bytes"].get<uint64_t>()));
  }
  out += fmt::format("{:>5} {:>12} {:>8} {:>12}\n", "total", "", total_tiles,
                     format_bytes(total_bytes));
  out += fmt::format("compression  {:.2f}:1 against {} raw\n", ratio,
                     format_bytes(total_tiles * raw_tile));
  std::fputs(out.c_str(), stdout);
  return 0;
}

}  // namespace relief::cli
