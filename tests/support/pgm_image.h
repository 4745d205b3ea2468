#pragma once
// A binary PGM (P5, 8 bit), as `pdftoppm -gray` writes it: the page tests read rendered PDF
// pages through it (tests/analysis/test_spec_report.cpp, tests/study/test_campaign_report_pdf.cpp).
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace doorbench::testing {

struct GrayImage {
  int width = 0, height = 0;
  std::vector<unsigned char> pixels;  // row by row
  unsigned char at(int x, int y) const {
    return pixels[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                  static_cast<std::size_t>(x)];
  }
};

inline GrayImage read_pgm(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string magic;
  int max_value = 0;
  GrayImage image;
  in >> magic >> image.width >> image.height >> max_value;
  in.get();  // the one whitespace before the pixels
  REQUIRE(magic == "P5");
  REQUIRE(max_value == 255);
  image.pixels.resize(static_cast<std::size_t>(image.width) * image.height);
  in.read(reinterpret_cast<char*>(image.pixels.data()),
          static_cast<std::streamsize>(image.pixels.size()));
  REQUIRE(in.good());
  return image;
}

// Pixels darker than 200 (ink) in the page's outer `margin_px` columns on the right.
inline int ink_in_right_margin(const GrayImage& page, int margin_px) {
  int ink = 0;
  for (int y = 0; y < page.height; ++y)
    for (int x = page.width - margin_px; x < page.width; ++x) ink += page.at(x, y) < 200 ? 1 : 0;
  return ink;
}

}  // namespace doorbench::testing
