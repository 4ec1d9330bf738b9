#pragma once
// OpenEXR output: named 32-bit float channels of one image, row-major, top row first.
#include <filesystem>
#include <string>
#include <vector>

namespace polrig {

struct ExrChannel {
  std::string name;
  std::vector<float> pixels;  // width × height
};

// Throws std::runtime_error naming the file when OpenEXR cannot write it.
void write_exr(const std::filesystem::path& path, int width, int height,
               const std::vector<ExrChannel>& channels);

// Reads the named channels back (for tests and users' checks).
std::vector<ExrChannel> read_exr(const std::filesystem::path& path, int& width, int& height);

}  // namespace polrig
