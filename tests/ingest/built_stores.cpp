#include "built_stores.h"

#include <gtest/gtest.h>

#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>

#include "../support/test_support.h"

namespace relief::testing {

namespace {
struct Entry {
  std::unique_ptr<ScratchDir> dir;
  std::unique_ptr<tiles::Store> store;
};
std::map<std::string, Entry>& registry() {
  static std::map<std::string, Entry> r;
  return r;
}
}  // namespace

const tiles::Store& built_store(const std::string& name, ingest::BuildOptions options) {
  auto& r = registry();
  if (auto it = r.find(name); it != r.end()) return *it->second.store;
  Entry e;
  e.dir = std::make_unique<ScratchDir>("store_" + name);
  options.output = e.dir->path() / name;
  ThreadExecutor executor;
  NullProgress progress;
  auto report = ingest::build_store(options, executor, progress);
  if (!report) throw std::runtime_error("building " + name + ": " + report.error().message);
  auto store = tiles::Store::open(options.output);
  if (!store) throw std::runtime_error(store.error().message);
  e.store = std::make_unique<tiles::Store>(std::move(*store));
  return *r.emplace(name, std::move(e)).first->second.store;
}

std::vector<std::string> pyrenees_inputs() {
  return {data("srtm/N41E001.hgt.zip"), data("srtm/N42E001.hgt.zip")};
}

const tiles::Store& srtm_store(const std::string& tile) {
  ingest::BuildOptions o;
  o.inputs = {data("srtm/" + tile + ".hgt.zip")};
  o.kind = tiles::DatasetKind::Elevation;
  return built_store(tile, o);
}

const tiles::Store& pyrenees_store() {
  ingest::BuildOptions o;
  o.inputs = pyrenees_inputs();
  o.kind = tiles::DatasetKind::Elevation;
  return built_store("pyrenees", o);
}

tiles::Tile must_read(const tiles::Store& store, const geo::TileKey& key) {
  auto tile = store.read_tile(key);
  if (!tile) throw std::runtime_error(tile.error().message);
  return std::move(*tile);
}

}  // namespace relief::testing
