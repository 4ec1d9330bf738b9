#pragma once
// OpenEXR output: named 32-bit float and unsigned-integer channels of one image, row-major, top
// row first, and header attributes.
#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace polrig {

struct ExrChannel {
  std::string name;
  std::vector<float> pixels;  // width × height
};

// Lossless every way: ZIP (zlib over blocks of 16 lines; the smallest for smooth images, slow),
// PIZ (Haar wavelet and Huffman over blocks of 32 lines; the smallest for noisy camera frames:
// 0.79× ZIP's bytes for the han2017 indoor frames, docs/formats.md §6.14), RLE (run lengths of
// the byte planes; for a 1024² sky map 1.3× ZIP's size, 5× faster) or none.
enum class ExrCompression { Zip, Piz, Rle, None };

// Throws std::runtime_error naming the file when OpenEXR cannot write it.
void write_exr(const std::filesystem::path& path, int width, int height,
               const std::vector<ExrChannel>& channels,
               ExrCompression compression = ExrCompression::Zip);

// An image's size in pixels.
struct ExrSize {
  int width = 0, height = 0;
};
// The largest side a reader accepts when no size is expected: the cameras' limit (device.width_px,
// height_px ≤ 16384), checked, like an expected size, from the header before any pixel is allocated.
inline constexpr int kMaxExrSide = 16384;

// Reads the named channels back (for tests and users' checks). With `expected`, a header of
// another size is refused (DataError "FILE: N × M px (expected W × H)") before any pixel is
// allocated; without it, a side beyond kMaxExrSide is.
std::vector<ExrChannel> read_exr(const std::filesystem::path& path, int& width, int& height,
                                 std::optional<ExrSize> expected = std::nullopt);

// A 32-bit unsigned-integer channel (OpenEXR's UINT): raw counts, stored exactly.
struct ExrUintChannel {
  std::string name;
  std::vector<std::uint32_t> pixels;  // width × height
};

// Header attributes: strings, doubles and 3-vectors (OpenEXR's string, double and V3d).
struct ExrAttributes {
  std::vector<std::pair<std::string, std::string>> strings;
  std::vector<std::pair<std::string, double>> doubles;
  std::vector<std::pair<std::string, std::array<double, 3>>> vectors;

  // The double attribute `name`, or nothing when the header has none.
  std::optional<double> number(std::string_view name) const {
    for (const auto& [key, value] : doubles)
      if (key == name) return value;
    return std::nullopt;
  }
};

// An image with both kinds of channel and its attributes.
struct ExrImage {
  int width = 0, height = 0;
  std::vector<ExrChannel> floats;
  std::vector<ExrUintChannel> uints;
  ExrAttributes attributes;
};

// Where an image's line blocks are compressed or decompressed: on OpenEXR's global pool, sized to
// the threads polrig may use (one image at a time), or on the calling thread alone (the pool is
// set to no threads for it, and sized again by the next pooled call), for callers that handle
// several images at once on their own threads (side_by_side.h, a parallel loop over stops): a
// pooled image there would leave its thread waiting for the pool's. The same bytes either way.
enum class ExrThreads { Pool, ThisThread };

// Writes every channel of `image` (lossless `compression`) and its attributes. Throws as write_exr.
void write_exr_image(const std::filesystem::path& path, const ExrImage& image,
                     ExrCompression compression = ExrCompression::Zip, ExrThreads threads = ExrThreads::Pool);
// Reads an image back: FLOAT and HALF channels as floats, UINT channels as uints, and the string,
// double, float, int and V3d attributes (float and int as doubles). Throws naming the file; the
// size is checked from the header first, as read_exr's.
ExrImage read_exr_image(const std::filesystem::path& path, std::optional<ExrSize> expected = std::nullopt,
                        ExrThreads threads = ExrThreads::Pool);
// Rows [first_row, first_row + rows) of an image (row 0: the data window's top), as read_exr_image
// but with height `rows`; only the line blocks holding them are decompressed; *image_height (when
// given) is the whole image's. Throws naming the file, also for rows outside the image; the whole
// image's size is checked from the header first, as read_exr's.
ExrImage read_exr_rows(const std::filesystem::path& path, int first_row, int rows, int* image_height = nullptr,
                       std::optional<ExrSize> expected = std::nullopt, ExrThreads threads = ExrThreads::Pool);

}  // namespace polrig
