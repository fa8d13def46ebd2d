// The renderer's GPU cache and its helpers, on a headless context: tile
// slots (texture-array layers, least recently used out, pins, growth
// announced ahead), the texture array's growth, the height slopes' half
// floats and their shader, and the quad records' nearness order.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <set>

#include <fmt/format.h>

#include "../ingest/built_stores.h"
#include "headless_gl.h"
#include "height_slopes.h"
#include "quad_records.h"
#include "tile_slots.h"

namespace relief::render {
namespace {

using geo::TileKey;

// The GPU cache (L3) as texture-array layers: within its budget least
// recently used first out, layers reused, the frame's tiles pinned.
TEST(TileSlots, EvictsTheLeastRecentlyUsedAndReusesTheirLayers) {
  headless_gl();
  const std::vector<float> pixels(4 * 4, 1.0f);  // 64 bytes of heights, 64 of slopes
  TileSlots slots(3 * 128, 4);
  gl::Uploads uploads;
  auto key = [](uint32_t x) { return TextureKey{TileKey{5, x, 0}, false}; };
  slots.begin_frame();
  for (uint32_t x = 0; x < 3; ++x) ASSERT_TRUE(slots.insert(key(x), 4, 4, pixels.data(), uploads));
  EXPECT_EQ(slots.used_bytes(), 3u * 128);
  EXPECT_EQ(uploads.textures, 3u * 128);
  EXPECT_EQ(slots.slopes().layers(), slots.heights().layers());
  EXPECT_EQ(slots.heights().layers(), 4);  // as many as the budget holds, at most the GL limit
  slots.begin_frame();
  ASSERT_TRUE(slots.find(key(0)));  // pinned, most recent
  const int layer1 = *slots.find(key(1));
  slots.begin_frame();
  ASSERT_TRUE(slots.find(key(0)));
  ASSERT_TRUE(slots.insert(key(3), 4, 4, pixels.data(), uploads));  // evicts 2, the oldest
  ASSERT_TRUE(slots.insert(key(4), 4, 4, pixels.data(), uploads));  // evicts 1
  EXPECT_FALSE(slots.find(key(1)));
  EXPECT_FALSE(slots.find(key(2)));
  EXPECT_EQ(slots.evicted(), 2u);
  EXPECT_EQ(slots.count(), 3u);
  EXPECT_LE(slots.used_bytes(), slots.budget_bytes());
  // Evicted layers are reused: nothing grew.
  EXPECT_EQ(slots.heights().layers(), 4);
  EXPECT_TRUE(*slots.find(key(3)) == layer1 || *slots.find(key(4)) == layer1);
  // Tiles of another size, and more pinned tiles than layers, are errors.
  const std::vector<float> big(8 * 8, 0.0f);
  auto wrong = slots.insert(key(9), 8, 8, big.data(), uploads);
  ASSERT_FALSE(wrong);
  EXPECT_NE(wrong.error().message.find("8x8, the store's others 4x4"), std::string::npos);
  slots.begin_frame();
  for (uint32_t x = 10; x < 14; ++x)
    ASSERT_TRUE(slots.insert(key(x), 4, 4, pixels.data(), uploads));
  auto full = slots.insert(key(14), 4, 4, pixels.data(), uploads);
  ASSERT_FALSE(full);
  EXPECT_NE(full.error().message.find("more than 4 elevation tiles"), std::string::npos);
}

// The texels of one layer of a texture array of R32F 4 x 4 layers.
std::vector<float> layer_texels(const gl::TextureArray& a, int layer) {
  std::vector<float> out(static_cast<size_t>(a.width()) * a.height());
  glGetTextureSubImage(a.id(), 0, 0, 0, layer, a.width(), a.height(), 1, GL_RED, GL_FLOAT,
                       static_cast<GLsizei>(out.size() * sizeof(float)), out.data());
  return out;
}

TEST(TextureArray, GrowsWithoutLosingItsLayers) {
  headless_gl();
  gl::TextureArray a(GL_R32F, GL_RED, GL_FLOAT, 4);
  a.set_layer_size(4, 4);
  a.reserve(2);
  gl::Uploads uploads;
  const std::vector<float> ones(16, 1.0f), twos(16, 2.0f);
  a.upload(0, ones.data(), uploads);
  a.upload(1, twos.data(), uploads);
  a.reserve(5);
  EXPECT_EQ(a.layers(), 5);
  EXPECT_EQ(layer_texels(a, 0), ones);
  EXPECT_EQ(layer_texels(a, 1), twos);
  EXPECT_EQ(uploads.textures, 2u * 64);  // the copy is GPU to GPU
  EXPECT_EQ(gl_error(), "");
}

// A full array of uploaded tiles is not copied into a larger one while the
// frame pins fewer than half its layers: the least recently used unpinned
// layer is reused. It grows (keeping every layer) once a frame pins half.
TEST(TileSlots, AFullArrayReusesALayerUnlessTheFramePinsHalfOfIt) {
  headless_gl();
  TileSlots slots(uint64_t{1} << 30, 4096);
  gl::Uploads uploads;
  auto key = [](uint32_t x) { return TextureKey{TileKey{12, x, 0}, false}; };
  auto pixels = [](uint32_t x) { return std::vector<float>(16, static_cast<float>(x)); };
  const uint32_t n = TileSlots::kFirstLayers;
  std::vector<int> layer_of;
  slots.begin_frame();
  for (uint32_t x = 0; x < n; ++x) {
    auto layer = slots.insert(key(x), 4, 4, pixels(x).data(), uploads);
    ASSERT_TRUE(layer);
    layer_of.push_back(*layer);
  }
  EXPECT_EQ(slots.heights().layers(), static_cast<int>(n));  // one allocation, no growth
  EXPECT_EQ(slots.pinned(false), static_cast<int>(n));
  // The next frame pins a quarter of the tiles and needs one more: tile n/4,
  // the least recently used of the others, gives its layer.
  slots.begin_frame();
  for (uint32_t x = 0; x < n / 4; ++x) ASSERT_TRUE(slots.find(key(x)));
  EXPECT_EQ(slots.pinned(false), static_cast<int>(n / 4));
  auto added = slots.insert(key(n), 4, 4, pixels(n).data(), uploads);
  ASSERT_TRUE(added);
  EXPECT_EQ(*added, layer_of[n / 4]);
  EXPECT_EQ(slots.heights().layers(), static_cast<int>(n));
  EXPECT_FALSE(slots.find(key(n / 4)));
  EXPECT_EQ(slots.evicted(), 1u);
  EXPECT_EQ(layer_texels(slots.heights(), *added), pixels(n));
  EXPECT_EQ(slots.slopes().layers(), static_cast<int>(n));
  // A frame that pins half the layers makes the array grow; no layer is lost.
  slots.begin_frame();
  for (uint32_t x = n / 2; x < n; ++x) ASSERT_TRUE(slots.find(key(x)));
  ASSERT_TRUE(slots.insert(key(n + 1), 4, 4, pixels(n + 1).data(), uploads));
  EXPECT_EQ(slots.heights().layers(), static_cast<int>(2 * n));
  EXPECT_EQ(slots.slopes().layers(), static_cast<int>(2 * n));
  EXPECT_EQ(slots.evicted(), 1u);
  for (uint32_t x : {0u, n / 2, n - 1, n, n + 1}) {
    const auto layer = slots.find(key(x));
    ASSERT_TRUE(layer) << x;
    EXPECT_EQ(layer_texels(slots.heights(), *layer), pixels(x)) << x;
  }
}

// Allocated ahead of the first tile (the renderer knows the store's tile
// size): the tiles then take free layers, nothing grows, and a tile of
// another size is refused as before.
TEST(TileSlots, AllocatedAheadTheFirstTilesTakeItsLayers) {
  headless_gl();
  TileSlots slots(uint64_t{1} << 30, 4096);
  slots.allocate(false, 4, 4);
  const int n = TileSlots::kFirstLayers;
  EXPECT_EQ(slots.heights().layers(), n);
  EXPECT_EQ(slots.slopes().layers(), n);
  EXPECT_EQ(slots.imagery().layers(), 0);
  EXPECT_EQ(slots.count(), 0u);
  EXPECT_EQ(slots.used_bytes(), 0u);
  slots.allocate(false, 8, 8);  // sized already: nothing
  EXPECT_EQ(slots.heights().width(), 4);
  gl::Uploads uploads;
  slots.begin_frame();
  const std::vector<float> pixels(16, 3.0f);
  auto layer = slots.insert(TextureKey{TileKey{3, 1, 0}, false}, 4, 4, pixels.data(), uploads);
  ASSERT_TRUE(layer);
  EXPECT_EQ(*layer, 0);
  EXPECT_EQ(layer_texels(slots.heights(), *layer), pixels);
  EXPECT_EQ(slots.heights().layers(), n);
  EXPECT_EQ(uploads.textures, 16u * (4 + 4));
  EXPECT_FALSE(slots.insert(TextureKey{TileKey{3, 2, 0}, false}, 5, 4, pixels.data(), uploads));
  EXPECT_EQ(gl_error(), "");
}

// The next growth's bytes are announced once per size, when a frame pins
// 3/8 of an array's layers (uploaded tiles grow once a frame pins half of a
// full array), for the heights' array and their slopes' apart.
TEST(TileSlots, AnnouncesTheNextGrowthBeforeItComes) {
  headless_gl();
  TileSlots slots(uint64_t{1} << 30, 4096);
  std::vector<uint64_t> announced;
  slots.set_on_growth_ahead([&](uint64_t bytes) { announced.push_back(bytes); });
  gl::Uploads uploads;
  const std::vector<float> pixels(16, 1.0f);
  const uint64_t n = TileSlots::kFirstLayers;
  auto insert = [&](uint64_t x) {
    return slots.insert(TextureKey{TileKey{12, static_cast<uint32_t>(x), 0}, false}, 4, 4,
                        pixels.data(), uploads);
  };
  slots.begin_frame();
  for (uint64_t x = 0; x + 1 < 3 * n / 8; ++x) ASSERT_TRUE(insert(x));
  EXPECT_TRUE(announced.empty());
  ASSERT_TRUE(insert(3 * n / 8 - 1));
  // 2n layers of 4 x 4 texels: R32F heights and RG16F slopes.
  EXPECT_EQ(announced, (std::vector<uint64_t>{2 * n * 64, 2 * n * 64}));
  for (uint64_t x = 3 * n / 8; x < n; ++x) ASSERT_TRUE(insert(x));
  EXPECT_EQ(announced.size(), 2u);
  EXPECT_EQ(slots.heights().layers(), static_cast<int>(n));
  // The frame needs one more: the array grows as announced, and with n + 1
  // of its 2n layers pinned the growth after is announced.
  ASSERT_TRUE(insert(n));
  EXPECT_EQ(slots.heights().layers(), static_cast<int>(2 * n));
  EXPECT_EQ(announced, (std::vector<uint64_t>{2 * n * 64, 2 * n * 64, 4 * n * 64, 4 * n * 64}));
  ASSERT_TRUE(insert(n + 1));
  EXPECT_EQ(announced.size(), 4u);
  EXPECT_EQ(gl_error(), "");
}

// Tiles found resident count as the frame's pins too; a growth past what
// the budget holds is not announced.
TEST(TileSlots, AnnouncesOnFoundTilesAndNotPastTheBudget) {
  headless_gl();
  const uint64_t n = TileSlots::kFirstLayers, tile = 4 * 4 * (4 + 4);
  TileSlots slots(2 * n * tile + tile, 4096);  // 2n layers and one more
  std::vector<uint64_t> announced;
  slots.set_on_growth_ahead([&](uint64_t bytes) { announced.push_back(bytes); });
  gl::Uploads uploads;
  const std::vector<float> pixels(16, 1.0f);
  auto insert = [&](uint64_t x) {
    return slots.insert(TextureKey{TileKey{12, static_cast<uint32_t>(x), 0}, false}, 4, 4,
                        pixels.data(), uploads);
  };
  auto find = [&](uint64_t x) {
    return slots.find(TextureKey{TileKey{12, static_cast<uint32_t>(x), 0}, false});
  };
  const uint64_t third = 3 * n / 8;  // pins that announce
  slots.begin_frame();
  for (uint64_t x = 0; x + 1 < third; ++x) ASSERT_TRUE(insert(x));
  EXPECT_TRUE(announced.empty());
  slots.begin_frame();
  ASSERT_TRUE(insert(third - 1));
  for (uint64_t x = 0; x + 2 < third; ++x) ASSERT_TRUE(find(x));
  EXPECT_TRUE(announced.empty());
  ASSERT_TRUE(find(third - 2));  // the frame's 3/8th pin, found
  EXPECT_EQ(announced, (std::vector<uint64_t>{2 * n * 64, 2 * n * 64}));
  // A frame of new tiles grows the array to 2n; pinning 3/8 of that, the
  // next growth would be past the budget: not announced.
  announced.clear();
  slots.begin_frame();
  for (uint64_t x = 1000; x <= 1000 + n; ++x) ASSERT_TRUE(insert(x));
  EXPECT_EQ(slots.heights().layers(), static_cast<int>(2 * n));
  EXPECT_GE(8 * slots.pinned(false), static_cast<int>(3 * 2 * n));
  EXPECT_TRUE(announced.empty());
  EXPECT_EQ(gl_error(), "");
}

// Composites (written on the GPU, costly to remake) are kept: their array
// grows, up to what the budget holds, rather than reuse a layer.
TEST(TileSlots, CompositesGrowTheArrayRatherThanGiveUpALayer) {
  headless_gl();
  TileSlots slots(uint64_t{1} << 30, 4096);
  gl::Uploads uploads;
  auto key = [](uint32_t x) { return TextureKey{TileKey{12, x, 0}, true, 1}; };
  const uint32_t n = TileSlots::kFirstLayers;
  slots.begin_frame();
  for (uint32_t x = 0; x < n; ++x) ASSERT_TRUE(slots.insert(key(x), 4, 4, nullptr, uploads));
  slots.begin_frame();
  ASSERT_TRUE(slots.insert(key(n), 4, 4, nullptr, uploads));
  EXPECT_EQ(slots.imagery().layers(), static_cast<int>(2 * n));
  EXPECT_EQ(slots.evicted(), 0u);
  EXPECT_EQ(uploads.textures, 0u);
}

TEST(HeightSlopes, HalfFloatsRoundToNearestEvenAndSaturate) {
  EXPECT_EQ(to_half(0.0f), 0x0000);
  EXPECT_EQ(to_half(-0.0f), 0x8000);
  EXPECT_EQ(to_half(1.0f), 0x3c00);
  EXPECT_EQ(to_half(-2.0f), 0xc000);
  EXPECT_EQ(to_half(0.1f), 0x2e66);
  EXPECT_EQ(to_half(1234.5f), 0x64d2);          // (1 + 210.5 / 1024) * 2^10: a tie, to 210 (even)
  EXPECT_EQ(to_half(1.0f + 0x1p-11f), 0x3c00);  // half an ulp above 1: to 1 (even)
  EXPECT_EQ(to_half(1.0f + 3 * 0x1p-11f), 0x3c02);  // 1.5 ulps: to 2 ulps (even)
  EXPECT_EQ(to_half(65504.0f), 0x7bff);
  EXPECT_EQ(to_half(1e9f), 0x7bff);  // saturates: a slope, never infinite
  EXPECT_EQ(to_half(-1e9f), 0xfbff);
  EXPECT_EQ(to_half(0x1p-24f), 0x0001);  // the smallest subnormal
  EXPECT_EQ(to_half(0x1p-14f), 0x0400);  // the smallest normal
  EXPECT_EQ(to_half(std::nanf("")), 0x0000);
}

TEST(HeightSlopes, DifferencesAcrossEachSampleClampedAtTheEdges) {
  // 3 x 2 heights, rows running south.
  const std::vector<float> h = {1, 2,  4,  //
                                8, 16, 32};
  const std::vector<uint16_t> s = height_slopes(h, 3, 2);
  ASSERT_EQ(s.size(), 12u);
  const float expected[12] = {2 - 1,  8 - 1, 4 - 1,  16 - 2, 4 - 2,   32 - 4,  //
                              16 - 8, 8 - 1, 32 - 8, 16 - 2, 32 - 16, 32 - 4};
  for (size_t i = 0; i < 12; ++i) EXPECT_EQ(s[i], to_half(expected[i])) << i;
}

// The interior rows take a vectorised path (eight samples at a time where
// the CPU converts to half floats itself): every half equals to_half() of
// the clamped differences, saturation, NaN, subnormals and -0 included.
TEST(HeightSlopes, EveryPathGivesTheHalvesOfTheClampedDifferences) {
  std::mt19937 rng(3);
  for (const auto& [w, h] :
       {std::pair{37, 9}, std::pair{514, 6}, std::pair{8, 4}, std::pair{2, 5}}) {
    std::vector<float> heights(static_cast<size_t>(w) * h);
    for (float& v : heights) {
      switch (rng() % 6) {
        case 0:
          v = std::nanf("");
          break;
        case 1:
          v = rng() % 2 ? 1e9f : -1e9f;
          break;
        case 2:
          v = std::ldexp(static_cast<float>(rng() % 100), -30);
          break;
        case 3:
          v = -0.0f;
          break;
        default:
          v = static_cast<float>(rng() % 100000) / 7.0f - 5000.0f;
      }
    }
    auto at = [&](int x, int y) {
      return heights[static_cast<size_t>(std::clamp(y, 0, h - 1)) * w + std::clamp(x, 0, w - 1)];
    };
    const std::vector<uint16_t> s = height_slopes(heights, w, h);
    ASSERT_EQ(s.size(), heights.size() * 2);
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const size_t i = (static_cast<size_t>(y) * w + x) * 2;
        ASSERT_EQ(s[i], to_half(at(x + 1, y) - at(x - 1, y)))
            << w << "x" << h << " " << x << "," << y;
        ASSERT_EQ(s[i + 1], to_half(at(x, y + 1) - at(x, y - 1)))
            << w << "x" << h << " " << x << "," << y;
      }
    }
  }
}

// What the fragment shader shades with, on real tiles through the GL's own
// filtering: the one fetch of the slopes gives the height differences (and
// the shade) of the four fetches of the heights it replaces, anywhere in the
// tile, edges included.
TEST(HeightSlopes, OneFetchShadesAsTheFourHeightFetchesItReplaces) {
  headless_gl();
  const char* source = R"(#version 450 core
layout(local_size_x = 64) in;
uniform sampler2DArray heights, slopes;
uniform int layer, border;
layout(std430, binding = 0) readonly buffer Points { vec2 points[]; };
layout(std430, binding = 1) writeonly buffer Results { vec4 results[]; };
vec3 at(sampler2DArray t, vec2 p) {
  return vec3((p + float(border)) / vec2(textureSize(t, 0).xy), float(layer));
}
float h(vec2 p) { return textureLod(heights, at(heights, p), 0.0).r; }
void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= uint(points.length())) return;
  vec2 p = points[i];
  results[i] = vec4(h(p + vec2(1, 0)) - h(p - vec2(1, 0)), h(p + vec2(0, 1)) - h(p - vec2(0, 1)),
                    textureLod(slopes, at(slopes, p), 0.0).rg);
}
)";
  const GLuint shader = glCreateShader(GL_COMPUTE_SHADER);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  ASSERT_TRUE(ok);
  const GLuint program = glCreateProgram();
  glAttachShader(program, shader);
  glLinkProgram(program);
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  ASSERT_TRUE(ok);

  const lod::MeshTopology mesh(3);
  lod::TerrainModel terrain(&testing::pyrenees_store(), mesh, uint64_t{256} << 20);
  const int finest = terrain.data_max_level();
  TileSlots slots(uint64_t{1} << 30, 16);
  gl::Uploads uploads;
  slots.begin_frame();
  // Steep tiles of the Pyrenees: the finest level, and four levels up.
  for (int level : {finest, finest - 4}) {
    SCOPED_TRACE(level);
    const uint32_t n = 1u << level;
    const TileKey key{level, static_cast<uint32_t>((1.6 + 180) / 360 * n),
                      static_cast<uint32_t>((90 - 42.6) / 180 * n)};
    auto tile = terrain.tile(key);
    ASSERT_TRUE(tile && *tile) << key.to_string();
    auto layer = slots.insert({key, false}, (*tile)->width(), (*tile)->height(),
                              (*tile)->f32().data(), uploads);
    ASSERT_TRUE(layer) << layer.error().message;
    // Points in interior sample coordinates, as the vertex shader passes
    // them: random ones, and the corners and sides of the tile.
    const float w = static_cast<float>(terrain.tile_width()),
                hh = static_cast<float>(terrain.tile_height());
    std::vector<float> points = {0,     0, w, 0,      0, hh,     w,     hh,
                                 w / 2, 0, 0, hh / 2, w, hh / 2, w / 2, hh};
    std::mt19937 random(7);
    std::uniform_real_distribution<float> u(0, 1);
    while (points.size() < 2 * 4096) points.insert(points.end(), {u(random) * w, u(random) * hh});
    const size_t count = points.size() / 2;
    GLuint buffers[2];
    glCreateBuffers(2, buffers);
    glNamedBufferStorage(buffers[0], static_cast<GLsizeiptr>(points.size() * sizeof(float)),
                         points.data(), 0);
    glNamedBufferStorage(buffers[1], static_cast<GLsizeiptr>(count * 4 * sizeof(float)), nullptr,
                         0);
    glUseProgram(program);
    glBindTextureUnit(0, slots.heights().id());
    glBindTextureUnit(1, slots.slopes().id());
    glUniform1i(glGetUniformLocation(program, "heights"), 0);
    glUniform1i(glGetUniformLocation(program, "slopes"), 1);
    glUniform1i(glGetUniformLocation(program, "layer"), *layer);
    glUniform1i(glGetUniformLocation(program, "border"), terrain.border());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, buffers[0]);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, buffers[1]);
    glDispatchCompute(static_cast<GLuint>((count + 63) / 64), 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    std::vector<float> results(count * 4);
    glGetNamedBufferSubData(buffers[1], 0, static_cast<GLsizeiptr>(results.size() * sizeof(float)),
                            results.data());
    glDeleteBuffers(2, buffers);
    ASSERT_EQ(gl_error(), "");

    // The shade of the fragment shader (sun from the north-west, 45 degrees
    // up) for a sample spacing of this level at 42.6 degrees north.
    const double spacing = key.bounds().height() / terrain.tile_height() * M_PI / 180 * 6371000.0;
    auto shade = [&](double dx, double dy, double exaggeration) {
      dx *= exaggeration / (2 * spacing * std::cos(42.6 * M_PI / 180));
      dy *= exaggeration / (2 * spacing);
      const double normal = std::sqrt(dx * dx + dy * dy + 1), sun = std::sqrt(2 + 1.414 * 1.414);
      return std::clamp((dx + dy + 1.414) / (normal * sun), 0.0, 1.0);
    };
    double worst_metres = 0, worst_shade = 0, steepest = 0;
    for (size_t i = 0; i < count; ++i) {
      const float* r = &results[4 * i];
      // The differences themselves differ by the GL's sub-texel precision
      // (llvmpipe: 8-bit filter weights) times the differences between texels.
      worst_metres =
          std::max({worst_metres, std::abs(double{r[2]} - r[0]), std::abs(double{r[3]} - r[1])});
      steepest = std::max(steepest, std::abs(static_cast<double>(r[0])) / (2 * spacing));
      for (double e : {1.0, 3.0, 10.0}) {
        const double error = std::abs(shade(r[2], r[3], e) - shade(r[0], r[1], e));
        worst_shade = std::max(worst_shade, error);
        EXPECT_LT(error, 1e-3) << "at " << points[2 * i] << "," << points[2 * i + 1]
                               << ", exaggeration " << e;  // a quarter of a grey level
      }
    }
    EXPECT_GT(steepest, 0.5);  // steep terrain, not a flat test
    std::cout << fmt::format("level {}: differences within {:.4f} m, shade within {:.2e}\n", level,
                             worst_metres, worst_shade);
  }
  glDeleteProgram(program);
  glDeleteShader(shader);
}

// Draws go nearest quad first (so llvmpipe's depth test spares the shading
// of what is hidden): a large quad under the eye before a small one nearby,
// before a small one far away.
TEST(QuadRecords, NearnessOrdersTheQuadUnderTheEyeFirst) {
  auto key_at = [](int level, double lon, double lat) {
    const uint32_t n = 1u << level;
    return TileKey{level, static_cast<uint32_t>((lon + 180) / 360 * n),
                   static_cast<uint32_t>((90 - lat) / 180 * n)};
  };
  QuadRecords records;
  const lod::Vec3 eye = lod::ecef(1.5, 42.5, 2000);
  const float under = nearness(records.make({key_at(6, 1.5, 42.5)}, eye)),
              nearby = nearness(records.make({key_at(12, 1.6, 42.5)}, eye)),
              far = nearness(records.make({key_at(12, 3, 42.5)}, eye));
  EXPECT_LT(under, nearby);
  EXPECT_LT(nearby, far);
  EXPECT_NEAR(far, 123000, 3000);  // 1.5 degrees of longitude at 42.5 north, less the quad's reach
}

}  // namespace
}  // namespace relief::render
