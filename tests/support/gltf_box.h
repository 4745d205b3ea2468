#pragma once
// A small glTF 2.0 file written by hand for the station's tests: one box, in its own units,
// as node `name` (the buffer embedded as a base64 data URI).
#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace doorbench::testing {

inline std::string base64(const std::vector<unsigned char>& bytes) {
  static const char* alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const unsigned b0 = bytes[i];
    const unsigned b1 = i + 1 < bytes.size() ? bytes[i + 1] : 0;
    const unsigned b2 = i + 2 < bytes.size() ? bytes[i + 2] : 0;
    const unsigned triple = (b0 << 16) | (b1 << 8) | b2;
    out += alphabet[(triple >> 18) & 63];
    out += alphabet[(triple >> 12) & 63];
    out += i + 1 < bytes.size() ? alphabet[(triple >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? alphabet[triple & 63] : '=';
  }
  return out;
}

// Writes a glTF with one node `name` holding the box [lo, hi] (36 vertices, no indices).
inline void write_gltf_box(const std::filesystem::path& path, const std::string& name,
                           std::array<float, 3> lo, std::array<float, 3> hi) {
  std::vector<float> positions;
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      std::array<std::array<float, 3>, 4> c{};
      const float us[4] = {lo[u], hi[u], hi[u], lo[u]};
      const float vs[4] = {lo[v], lo[v], hi[v], hi[v]};
      for (int k = 0; k < 4; ++k) {
        c[k][axis] = side == 0 ? lo[axis] : hi[axis];
        c[k][u] = us[k];
        c[k][v] = vs[k];
      }
      if (side == 0) std::swap(c[1], c[3]);
      for (const int k : {0, 1, 2, 0, 2, 3})
        positions.insert(positions.end(), c[k].begin(), c[k].end());
    }
  }
  std::vector<unsigned char> bytes(positions.size() * sizeof(float));
  std::memcpy(bytes.data(), positions.data(), bytes.size());
  std::ofstream out(path);
  out << R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
  "nodes": [{"name": ")"
      << name << R"(", "mesh": 0}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
  "buffers": [{"byteLength": )"
      << bytes.size() << R"(, "uri": "data:application/octet-stream;base64,)" << base64(bytes)
      << R"("}],
  "bufferViews": [{"buffer": 0, "byteLength": )"
      << bytes.size() << R"(}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": )"
      << positions.size() / 3 << R"(, "type": "VEC3", "min": [)" << lo[0] << ", " << lo[1] << ", "
      << lo[2] << R"(], "max": [)" << hi[0] << ", " << hi[1] << ", " << hi[2] << R"(]}]}
)";
}

}  // namespace doorbench::testing
