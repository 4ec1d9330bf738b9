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

// Lossless either way: ZIP (zlib over blocks of 16 lines; the smallest, slowest), RLE (run
// lengths of the byte planes; for a 1024² sky map 1.3× ZIP's size, 5× faster) or none.
enum class ExrCompression { Zip, Rle, None };

// Throws std::runtime_error naming the file when OpenEXR cannot write it.
void write_exr(const std::filesystem::path& path, int width, int height,
               const std::vector<ExrChannel>& channels,
               ExrCompression compression = ExrCompression::Zip);

// Reads the named channels back (for tests and users' checks).
std::vector<ExrChannel> read_exr(const std::filesystem::path& path, int& width, int& height);

}  // namespace polrig
