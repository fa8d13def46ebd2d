#pragma once
// A quantized-mesh-1.0 reader written from the format's specification
// (github.com/CesiumGS/quantized-mesh), not from relief's encoder: the tests
// read relief's tiles with it. Fails the current test on malformed input.
#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace relief::testing {

struct DecodedMesh {
  double centre[3], min_height, max_height, sphere[4], hop[3];
  std::vector<uint16_t> u, v, h;
  std::vector<uint32_t> indices;
  std::vector<uint32_t> west, south, east, north;
  bool wide_indices = false;
  std::vector<uint8_t> normals;  // extension 1, 2 bytes per vertex
  std::string metadata;          // extension 4's JSON
  int extensions = 0;
  double height(size_t i) const {  // as CesiumJS decodes it
    const double t = h[i] / 32767.0;
    return (1 - t) * min_height + t * max_height;
  }
};

inline std::vector<uint8_t> gunzip(const std::vector<std::byte>& in) {
  z_stream z{};
  EXPECT_EQ(inflateInit2(&z, 15 + 16), Z_OK);
  std::vector<uint8_t> out(in.size() * 8 + 1024);
  z.next_in = reinterpret_cast<Bytef*>(const_cast<std::byte*>(in.data()));
  z.avail_in = static_cast<uInt>(in.size());
  int rc = Z_OK;
  while (rc == Z_OK) {
    if (z.total_out == out.size()) out.resize(out.size() * 2);
    z.next_out = reinterpret_cast<Bytef*>(out.data() + z.total_out);
    z.avail_out = static_cast<uInt>(out.size() - z.total_out);
    rc = inflate(&z, Z_NO_FLUSH);
  }
  EXPECT_EQ(rc, Z_STREAM_END);
  out.resize(z.total_out);
  inflateEnd(&z);
  return out;
}

class SpecReader {
 public:
  explicit SpecReader(const std::vector<uint8_t>& b) : b_(b) {}
  template <class T>
  T get() {
    T v{};
    if (at_ + sizeof(T) > b_.size()) {
      ADD_FAILURE() << "quantized mesh ends early at byte " << at_;
      at_ = b_.size();
      return v;
    }
    std::memcpy(&v, b_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return v;
  }
  size_t at() const { return at_; }
  bool done() const { return at_ >= b_.size(); }

 private:
  const std::vector<uint8_t>& b_;
  size_t at_ = 0;
};

inline DecodedMesh decode_quantized_mesh(const std::vector<uint8_t>& bytes) {
  DecodedMesh m;
  SpecReader r(bytes);
  for (double& c : m.centre) c = r.get<double>();
  m.min_height = r.get<float>();
  m.max_height = r.get<float>();
  for (double& s : m.sphere) s = r.get<double>();
  for (double& p : m.hop) p = r.get<double>();
  const uint32_t n = r.get<uint32_t>();
  for (auto* array : {&m.u, &m.v, &m.h}) {
    int value = 0;
    for (uint32_t i = 0; i < n; ++i) {
      const uint16_t z = r.get<uint16_t>();
      value += (z >> 1) ^ (-(z & 1));
      array->push_back(static_cast<uint16_t>(value));
    }
  }
  m.wide_indices = n > 65536;
  if (m.wide_indices && r.at() % 4 != 0) {
    EXPECT_EQ(r.get<uint16_t>(), 0) << "padding";
  }
  auto index = [&]() -> uint32_t { return m.wide_indices ? r.get<uint32_t>() : r.get<uint16_t>(); };
  const uint32_t triangles = r.get<uint32_t>();
  uint32_t highest = 0;
  for (uint32_t i = 0; i < triangles * 3; ++i) {
    const uint32_t code = index();
    m.indices.push_back(highest - code);
    if (code == 0) ++highest;
  }
  for (auto* edge : {&m.west, &m.south, &m.east, &m.north}) {
    const uint32_t count = r.get<uint32_t>();
    for (uint32_t i = 0; i < count; ++i) edge->push_back(index());
  }
  while (!r.done()) {
    const uint8_t id = r.get<uint8_t>();
    const uint32_t length = r.get<uint32_t>();
    ++m.extensions;
    if (id == 1) {
      for (uint32_t i = 0; i < length; ++i) m.normals.push_back(r.get<uint8_t>());
    } else if (id == 4) {
      const uint32_t json = r.get<uint32_t>();
      EXPECT_EQ(json + 4, length);
      for (uint32_t i = 0; i < json; ++i) m.metadata.push_back(static_cast<char>(r.get<uint8_t>()));
    } else {
      for (uint32_t i = 0; i < length; ++i) r.get<uint8_t>();
    }
  }
  return m;
}

}  // namespace relief::testing
