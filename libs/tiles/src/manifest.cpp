#include "relief/tiles/manifest.h"

#include <cstdint>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "relief/tiles/store_layout.h"

namespace relief::tiles {

using nlohmann::json;

namespace {

// nlohmann's get<int>() converts a float or an out-of-range integer with a bare
// static_cast, which is undefined behaviour (UBSan under fuzz/manifest.cpp on
// "bands": 1e300): integer fields must hold an integer that fits.
template <class T>
T integer_at(const json& j, const char* key) {
  const json& v = j.at(key);
  if (v.is_number_unsigned() && std::in_range<T>(v.get<uint64_t>())) return v.get<T>();
  if (v.is_number_integer() && !v.is_number_unsigned() && std::in_range<T>(v.get<int64_t>())) {
    return v.get<T>();
  }
  throw std::out_of_range(fmt::format("'{}' must be an integer in [{}, {}], not {}", key,
                                      std::numeric_limits<T>::min(), std::numeric_limits<T>::max(),
                                      v.dump()));
}

}  // namespace

std::string predates_geometric_errors(const std::string& file) {
  // The store is the manifest's directory, or an index's level directory's parent.
  std::filesystem::path store = std::filesystem::path(file).parent_path();
  if (!file.ends_with(kManifestName)) store = store.parent_path();
  return fmt::format(
      "{}: the store predates geometric errors (store format version 1); upgrade it with "
      "`relief upgrade {}`",
      file, store.empty() ? std::string("STORE") : store.string());
}

std::optional<int> manifest_format_version(const std::string& text) {
  const json j = json::parse(text, nullptr, false);
  if (!j.is_object()) return std::nullopt;
  const auto format = j.find("format");
  if (format == j.end() || !format->is_string() || *format != "relief-store") return std::nullopt;
  const auto it = j.find("format_version");
  if (it == j.end() || !it->is_number_integer() || !std::in_range<int>(it->get<int64_t>())) {
    return std::nullopt;
  }
  return it->get<int>();
}

std::string_view to_string(DatasetKind k) {
  switch (k) {
    case DatasetKind::Elevation:
      return "elevation";
    case DatasetKind::Imagery:
      return "imagery";
    case DatasetKind::Sar:
      return "sar";
  }
  return "?";
}

Result<DatasetKind> dataset_kind_from_string(std::string_view s) {
  for (auto k : {DatasetKind::Elevation, DatasetKind::Imagery, DatasetKind::Sar}) {
    if (s == to_string(k)) return k;
  }
  return fail(fmt::format("unknown dataset kind '{}' (elevation, imagery, sar)", s));
}

std::string Manifest::nodata_description() const {
  return sample_type == SampleType::Float32 ? "NaN" : "alpha=0";
}

std::string Manifest::to_json() const {
  json j;
  j["format"] = "relief-store";
  j["format_version"] = format_version;
  j["kind"] = to_string(kind);
  j["sample_type"] = to_string(sample_type);
  j["bands"] = bands;
  j["units"] = units;
  j["nodata"] = nodata_description();
  j["tile"] = {{"width", 2 << tile_log2_height},
               {"height", 1 << tile_log2_height},
               {"border", border},
               {"registration", "cell-centre"}};
  j["levels"] = {{"min", min_level}, {"max", max_level}};
  j["extent"] = {{"west", extent.west},
                 {"south", extent.south},
                 {"east", extent.east},
                 {"north", extent.north}};
  j["statistics"] = {{"min", stats.min},
                     {"max", stats.max},
                     {"mean", stats.mean},
                     {"std", stats.stddev},
                     {"valid_samples", stats.valid_count}};
  j["codec"] = {
      {"name", to_string(codec.codec)}, {"max_error", codec.max_error}, {"quality", codec.quality}};
  json sources_json = json::array();
  for (const auto& s : sources) {
    sources_json.push_back({{"path", s.path},
                            {"crs", s.crs},
                            {"width", s.width},
                            {"height", s.height},
                            {"bands", s.bands},
                            {"data_type", s.data_type}});
  }
  j["sources"] = sources_json;
  j["created_by"] = created_by;
  if (sparse_depth) j["sparse_depth"] = true;
  return j.dump(2) + "\n";
}

Result<Manifest> Manifest::from_json(const std::string& text, const std::string& name) {
  try {
    const json j = json::parse(text);
    if (j.at("format").get<std::string>() != "relief-store") {
      return fail(fmt::format("{}: not a relief store manifest", name));
    }
    Manifest m;
    m.format_version = integer_at<int>(j, "format_version");
    if (m.format_version == 1) return fail(predates_geometric_errors(name));
    if (m.format_version != kStoreFormatVersion) {
      return fail(fmt::format("{}: unsupported store format version {}", name, m.format_version));
    }
    auto kind = dataset_kind_from_string(j.at("kind").get<std::string>());
    if (!kind) return fail(fmt::format("{}: {}", name, kind.error().message));
    m.kind = *kind;
    auto type = sample_type_from_string(j.at("sample_type").get<std::string>());
    if (!type) return fail(fmt::format("{}: {}", name, type.error().message));
    m.sample_type = *type;
    m.bands = integer_at<int>(j, "bands");
    m.units = j.at("units").get<std::string>();
    // A tile file stores its bordered width in 16 bits: 2^(k+1) + 2 border <= 65535.
    const int height = integer_at<int>(j.at("tile"), "height");
    m.border = integer_at<int>(j.at("tile"), "border");
    int log2 = 0;
    while (log2 < 14 && (1 << log2) < height) ++log2;
    if ((1 << log2) != height || integer_at<int>(j.at("tile"), "width") != 2 * height) {
      return fail(fmt::format("{}: tile size must be 2^(k+1) x 2^k, k <= 14", name));
    }
    if (m.border < 0 || m.border > (65535 - 2 * height) / 2) {
      return fail(fmt::format("{}: bad tile border {}", name, m.border));
    }
    m.tile_log2_height = log2;
    // Samples are cell-centred (docs/store-format.md): a reader of another
    // registration would place every sample half a sample off.
    if (const auto registration = j.at("tile").at("registration").get<std::string>();
        registration != "cell-centre") {
      return fail(fmt::format("{}: tile registration '{}' is not cell-centre", name, registration));
    }
    m.min_level = integer_at<int>(j.at("levels"), "min");
    m.max_level = integer_at<int>(j.at("levels"), "max");
    if (m.min_level < 0 || m.max_level > geo::kMaxLevel || m.min_level > m.max_level) {
      return fail(fmt::format("{}: bad level range", name));
    }
    const auto& e = j.at("extent");
    m.extent = {e.at("west").get<double>(), e.at("south").get<double>(), e.at("east").get<double>(),
                e.at("north").get<double>()};
    const auto& s = j.at("statistics");
    m.stats = {s.at("min").get<double>(), s.at("max").get<double>(), s.at("mean").get<double>(),
               s.at("std").get<double>(), integer_at<uint64_t>(s, "valid_samples")};
    auto codec = codec_from_string(j.at("codec").at("name").get<std::string>());
    if (!codec) return fail(fmt::format("{}: {}", name, codec.error().message));
    m.codec.codec = *codec;
    m.codec.max_error = j.at("codec").at("max_error").get<double>();
    m.codec.quality =
        j.at("codec").contains("quality") ? integer_at<int>(j.at("codec"), "quality") : 90;
    for (const auto& src : j.at("sources")) {
      m.sources.push_back({src.at("path").get<std::string>(), src.at("crs").get<std::string>(),
                           integer_at<int>(src, "width"), integer_at<int>(src, "height"),
                           integer_at<int>(src, "bands"), src.at("data_type").get<std::string>()});
    }
    m.created_by = j.value("created_by", "");
    m.sparse_depth = j.value("sparse_depth", false);
    RELIEF_CHECK(check_consistency(m, name));
    if (const auto nodata = j.at("nodata").get<std::string>(); nodata != m.nodata_description()) {
      return fail(fmt::format("{}: nodata '{}' is not {} samples' '{}'", name, nodata,
                              to_string(m.sample_type), m.nodata_description()));
    }
    return m;
  } catch (const json::exception& ex) {
    return fail(fmt::format("{}: invalid manifest: {}", name, ex.what()));
  } catch (const std::out_of_range& ex) {
    return fail(fmt::format("{}: invalid manifest: {}", name, ex.what()));
  }
}

}  // namespace relief::tiles
