// bench/tools/refine_bench: the edge-mark refinement (lod::refine, top-down)
// of the frames of a camera path, without drawing: what `relief view` spends
// on it per frame of a moving camera. The path is bench/view's flight (out
// and back at HEIGHT m between two points, looking ahead and down at 25
// degrees; the Pyrenees': 1.15 42.15 1.85 42.75 3000, 60 s), sampled at FPS
// frames per second of path time at 1280 x 720, 60 degrees; each frame selects (edge-mark mode,
// complete data) and refines with one RefineCache and, unless HISTORY=0, one
// RefineHistory, as view::Scene does. A first pass over the path measures
// every tile's diamond errors (so the timed pass measures none inline); the
// timed pass then starts from an empty history. SECONDS: only the path's
// first seconds. THREADS=N: refined in N lanes on a pool of N threads
// (RefineOptions::executor; the same meshes, so the same hash). Prints per-frame refinement
// wall and CPU time (median, mean, p90), marks evaluated and triangles in
// total, and a hash of every frame's index buffer: two builds that print the
// same hash drew the same meshes.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "relief/base/parallel.h"
#include "relief/lod/camera_path.h"
#include "relief/lod/refine.h"
#include "relief/lod/selection.h"

using namespace relief;

namespace {

double percentile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(p * static_cast<double>(v.size() - 1))];
}

uint64_t mix(uint64_t h, uint64_t v) {  // FNV-1a over 8-byte words
  return (h ^ v) * 0x100000001b3ull;
}

struct Totals {
  std::vector<double> wall_ms, cpu_ms;
  uint64_t marks = 0, reused = 0, triangles = 0, quads = 0, hash = 0xcbf29ce484222325ull;
};

Status fly(const std::vector<lod::Keyframe>& path, double fps, double end, double pixels,
           lod::TerrainModel& terrain, lod::RefineCache& cache, lod::RefineHistory* history,
           Executor* executor, Totals& totals, bool verbose) {
  lod::SelectionOptions so;
  so.pixel_error = pixels;
  so.mode = lod::LodMode::edge_marks;
  so.neighbour_indices = true;
  for (int frame = 0; frame / fps <= end; ++frame) {
    const lod::View view = RELIEF_TRY(lod::make_view(lod::camera_at(path, frame / fps)));
    terrain.begin_frame();
    const lod::Selection selection = RELIEF_TRY(lod::select_quads(view, terrain, so));
    terrain.end_frame();
    lod::RefineOptions ro;
    ro.pixel_error = pixels;
    ro.cache = &cache;
    ro.history = history;
    ro.executor = executor;
    const lod::RefinedMesh mesh = RELIEF_TRY(lod::refine(view, terrain, selection, ro));
    totals.wall_ms.push_back(mesh.stats.seconds * 1e3);
    totals.cpu_ms.push_back(mesh.stats.cpu_seconds * 1e3);
    totals.marks += mesh.stats.marks_evaluated;
    totals.reused += mesh.stats.marks_reused;
    totals.triangles += mesh.triangles();
    totals.quads += selection.quads.size();
    for (const uint32_t i : mesh.indices) totals.hash = mix(totals.hash, i);
    for (const lod::RefinedQuad& q : mesh.quads) {
      totals.hash = mix(totals.hash, uint64_t{q.first_index} << 32 | q.index_count);
    }
    if (verbose) {
      std::printf("frame %4d: %zu quads, %llu marks, %llu triangles, %.2f ms (cpu %.2f)\n", frame,
                  selection.quads.size(),
                  static_cast<unsigned long long>(mesh.stats.marks_evaluated),
                  static_cast<unsigned long long>(mesh.triangles()), mesh.stats.seconds * 1e3,
                  mesh.stats.cpu_seconds * 1e3);
    }
  }
  return {};
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 8 || argc > 10) {
    std::fprintf(
        stderr,
        "usage: refine_bench STORE LON0 LAT0 LON1 LAT1 HEIGHT PIXEL_ERROR [FPS [SECONDS]]\n");
    return 2;
  }
  const double lon0 = std::atof(argv[2]), lat0 = std::atof(argv[3]), lon1 = std::atof(argv[4]),
               lat1 = std::atof(argv[5]), height = std::atof(argv[6]);
  const double pixels = std::atof(argv[7]);
  const double fps = argc >= 9 ? std::atof(argv[8]) : 15.0;
  const double seconds = argc == 10 ? std::atof(argv[9]) : INFINITY;
  const char* env_history = std::getenv("HISTORY");
  const bool use_history = !env_history || std::string(env_history) != "0";
  const bool verbose = std::getenv("VERBOSE") != nullptr;
  const char* env_threads = std::getenv("THREADS");
  PooledExecutor pool(env_threads ? static_cast<unsigned>(std::atoi(env_threads)) : 1u);
  Executor* executor = pool.concurrency() > 1 ? &pool : nullptr;
  auto store = tiles::Store::open(argv[1]);
  if (!store) {
    std::fprintf(stderr, "%s\n", store.error().message.c_str());
    return 1;
  }
  // bench/view's flight_path: 60 s out and back with a turn at each end.
  constexpr double kDuration = 60, kPi = 3.14159265358979323846;
  const double heading = std::fmod(
      std::atan2((lon1 - lon0) * std::cos(lat0 * kPi / 180), lat1 - lat0) * 180 / kPi + 360, 360);
  const double half = kDuration / 2, turn = kDuration / 30;
  const auto camera = [](double lon, double lat, double h, double heading_deg) {
    return lod::Camera{lon, lat, h, heading_deg, -25, 0, 60, 1280, 720};
  };
  const std::vector<lod::Keyframe> keyframes = {
      {0, camera(lon0, lat0, height, heading), false},
      {half - turn, camera(lon1, lat1, height, heading), false},
      {half + turn, camera(lon1, lat1, height, std::fmod(heading + 180, 360)), false},
      {kDuration, camera(lon0, lat0, height, std::fmod(heading + 180, 360)), false},
  };
  const lod::MeshTopology topology(4);
  lod::TerrainModel terrain(&*store, topology, uint64_t{2} << 30);
  lod::RefineCache cache(uint64_t{2} << 30);
  const double end = std::min(seconds, keyframes.back().time);
  Totals warm, timed;
  lod::RefineHistory history;
  if (auto s = fly(keyframes, fps, end, pixels, terrain, cache, nullptr, executor, warm, false);
      !s) {
    std::fprintf(stderr, "%s\n", s.error().message.c_str());
    return 1;
  }
  if (auto s = fly(keyframes, fps, end, pixels, terrain, cache, use_history ? &history : nullptr,
                   executor, timed, verbose);
      !s) {
    std::fprintf(stderr, "%s\n", s.error().message.c_str());
    return 1;
  }
  double wall = 0, cpu = 0;
  for (size_t i = 0; i < timed.wall_ms.size(); ++i) {
    wall += timed.wall_ms[i];
    cpu += timed.cpu_ms[i];
  }
  const double n = static_cast<double>(timed.wall_ms.size());
  std::printf(
      "%zu frames at %.0f fps, %.1f px, history %s: refine ms wall p50 %.2f mean %.2f p90 %.2f, "
      "cpu p50 %.2f mean %.2f; %llu marks (%llu reused), %llu triangles, %llu quads; hash "
      "%016llx\n",
      timed.wall_ms.size(), fps, pixels, use_history ? "on" : "off", percentile(timed.wall_ms, 0.5),
      wall / n, percentile(timed.wall_ms, 0.9), percentile(timed.cpu_ms, 0.5), cpu / n,
      static_cast<unsigned long long>(timed.marks), static_cast<unsigned long long>(timed.reused),
      static_cast<unsigned long long>(timed.triangles),
      static_cast<unsigned long long>(timed.quads), static_cast<unsigned long long>(timed.hash));
  return 0;
}
