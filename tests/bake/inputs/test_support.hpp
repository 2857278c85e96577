// Helpers shared by the bake/inputs tests: a scratch directory per test, text and image writers.
#pragma once

#include <gtest/gtest.h>

#include <unistd.h>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <string>

#include "common/error.hpp"
#include "common/image_io/image_io.hpp"
#include "tests/support/scratch_dir.hpp"

namespace clothbake::testing {

// A fresh directory per test (tests/support/scratch_dir.hpp).
using ScratchDir = clothbake::test_support::ScratchDir;

inline void write_text(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

inline std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// Runs f, expects clothbake::Error with `code`, and returns its message.
template <class F>
std::string error_message(F&& f, ExitCode code = ExitCode::Input) {
  try {
    f();
  } catch (const Error& e) {
    EXPECT_EQ(int(e.code()), int(code)) << e.what();
    return e.what();
  }
  ADD_FAILURE() << "expected clothbake::Error, nothing was thrown";
  return {};
}

// An N x N image whose channels are filled by f(x, y, c).
template <class F>
Image make_image(int width, int height, int channels, F f) {
  Image im(width, height, channels);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < channels; ++c)
        im.at(x, y, c) = float(f(x, y, c));
  return im;
}

// A set of valid maps on disk (float EXR) for an image fabric of size n, plus a TOML file that
// names them; `extra` is appended to the TOML (more sections), `maps_extra` to [maps].
struct ImageFabric {
  std::string toml;
  int n = 8;
};

inline double test_height(int x, int y, int n) {
  return 0.02 * std::sin(2 * M_PI * x / n) + 0.01 * std::cos(2 * M_PI * y / n);
}

inline ImageFabric write_image_fabric(const ScratchDir& dir, int n = 8,
                                      const std::string& maps_extra = "",
                                      const std::string& extra = "") {
  write_image(dir / "height.exr",
              make_image(n, n, 1, [&](int x, int y, int) { return test_height(x, y, n); }),
              PixelType::Float32);
  // Fibres along x on even rows and along y on odd rows, slightly tilted up.
  write_image(dir / "tangent.exr",
              make_image(n, n, 3,
                         [&](int, int y, int c) {
                           double t[3] = {y % 2 == 0 ? 0.96 : 0.0, y % 2 == 0 ? 0.0 : 0.96, 0.28};
                           return t[c];
                         }),
              PixelType::Float32);
  ImageFabric f;
  f.n = n;
  f.toml = dir / "fabric.toml";
  write_text(
      f.toml,
      "name = \"test fabric\"\n[maps]\nheight = \"height.exr\"\ntangent = \"tangent.exr\"\n" +
          maps_extra + "\n" + extra);
  return f;
}

}  // namespace clothbake::testing
