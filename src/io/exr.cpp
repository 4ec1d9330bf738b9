#include "polrig/io/exr.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <span>
#include <stdexcept>

#include <ImfAttribute.h>
#include <ImfChannelList.h>
#include <ImfDoubleAttribute.h>
#include <ImfFloatAttribute.h>
#include <ImfIntAttribute.h>
#include <ImfStringAttribute.h>
#include <ImfVecAttribute.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfThreading.h>
#include <ImfStdIO.h>
#include <ImfVersion.h>
#include <fmt/format.h>

#include "polrig/io/measured.h"
#include "polrig/threads.h"

namespace polrig {

namespace {
// OpenEXR compresses and decompresses a file's line blocks on its global thread pool, which has
// no threads until told (OutputFile's thread count alone only sizes its line buffers: the
// compression then ran on the calling thread, one core busy with PIZ while H17's simulation
// waited). Sized to the threads polrig may use (--threads).
// OutputFile hands its line blocks to the global pool whatever thread count it is given (that
// count sizes its buffers): only a pool of no threads compresses on the calling thread. So the
// pool is sized per call: `usable_threads()` for one image at a time, none for callers that
// handle several at once on their own threads (ExrThreads::ThisThread). Resizing while another
// thread's image is on the pool is safe with Debian's OpenEXR 3.1 (setProvider waits for the
// pool's users and runs their queued blocks); the CLI never mixes the two at once, but two Python
// threads may (speed only). A fixed provider that runs a ThisThread caller's blocks inline would
// end the resizing (and is what OpenEXR ≥ 3.2, whose swap does not wait, would need).
int use_exr_threads(ExrThreads where) {
  static std::mutex mutex;
  const std::lock_guard lock(mutex);
  const int threads = where == ExrThreads::Pool ? usable_threads() : 0;
  if (Imf::globalThreadCount() != threads) Imf::setGlobalThreadCount(threads);
  return threads;
}

// OpenEXR's own file stream does not check its writes, and OutputFile writes its offset table
// in its destructor, where errors are swallowed: this stream remembers the first error (a full
// disk…) so that close() can report it with the system's reason.
class CheckedOStream : public Imf::OStream {
 public:
  explicit CheckedOStream(const std::filesystem::path& path)
      : Imf::OStream(path.c_str()), file_(std::fopen(path.c_str(), "wb")) {
    if (!file_) fail("cannot create the file");
  }
  ~CheckedOStream() override {
    if (file_) std::fclose(file_);
  }
  void write(const char c[], int n) override {
    if (std::fwrite(c, 1, static_cast<std::size_t>(n), file_) != static_cast<std::size_t>(n)) fail("cannot write the file");
  }
  uint64_t tellp() override {
    const off_t p = ::ftello(file_);
    if (p < 0) fail("cannot tell the position");
    return static_cast<uint64_t>(p);
  }
  void seekp(uint64_t pos) override {
    if (::fseeko(file_, static_cast<off_t>(pos), SEEK_SET) != 0) fail("cannot seek");
  }
  // Throws the first error seen, or the one of flushing and closing.
  void close() {
    std::FILE* f = file_;
    file_ = nullptr;
    if (std::fflush(f) != 0 && !error_) error_ = errno ? errno : EIO;
    if (std::fclose(f) != 0 && !error_) error_ = errno ? errno : EIO;
    if (error_) throw std::runtime_error(std::strerror(error_));
  }

 private:
  [[noreturn]] void fail(const char* what) {
    if (!error_) error_ = errno ? errno : EIO;
    throw std::runtime_error(fmt::format("{}: {}", what, std::strerror(error_)));
  }
  std::FILE* file_;
  int error_ = 0;
};
}  // namespace

namespace {
// The data window's size from the header, refused before any pixel is allocated: another size
// than `expected`, or (nothing expected) an empty image or a side beyond kMaxExrSide. Computed
// in 64 bits: a forged window does not overflow.
ExrSize claimed_size(const std::filesystem::path& path, const Imath::Box2i& dw, const std::optional<ExrSize>& expected) {
  const long long w = static_cast<long long>(dw.max.x) - dw.min.x + 1;
  const long long h = static_cast<long long>(dw.max.y) - dw.min.y + 1;
  const bool ok = expected ? w == expected->width && h == expected->height
                           : w >= 1 && h >= 1 && w <= kMaxExrSide && h <= kMaxExrSide;
  if (!ok)
    throw DataError(fmt::format("{}: {} × {} px (expected {})", path.string(), w, h,
                                expected ? fmt::format("{} × {}", expected->width, expected->height)
                                         : fmt::format("at most {} × {}", kMaxExrSide, kMaxExrSide)));
  return {static_cast<int>(w), static_cast<int>(h)};
}

// The size the file's (first) header claims, checked as claimed_size() checks it, reading only
// the magic number, the version field and the header's attributes: Imf::InputFile allocates its
// line buffers and line-offset table from the data window, and reads that table, before a caller
// could look at the header. A file this pass cannot read (missing, not an OpenEXR file, a header
// cut short) is left to Imf::InputFile, which says what is wrong with it.
void check_header_size(const std::filesystem::path& path, const std::optional<ExrSize>& expected) {
  Imf::Header header;
  try {
    Imf::StdIFStream in(path.string().c_str());
    char start[8];
    in.read(start, 8);
    if (!Imf::isImfMagic(start)) return;
    int version = 0;
    for (int i = 7; i >= 4; --i) version = (version << 8) | static_cast<unsigned char>(start[i]);  // little endian
    if (Imf::getVersion(version) != Imf::EXR_VERSION || !Imf::supportsFlags(Imf::getFlags(version))) return;
    header.readFrom(in, version);
  } catch (const std::exception&) {
    return;
  }
  claimed_size(path, header.dataWindow(), expected);
}
}  // namespace

std::vector<ExrChannel> read_exr(const std::filesystem::path& path, int& width, int& height,
                                 std::optional<ExrSize> expected) {
  try {
    check_header_size(path, expected);
    Imf::InputFile file(path.string().c_str());
    const Imath::Box2i dw = file.header().dataWindow();
    const ExrSize size = claimed_size(path, dw, expected);
    width = size.width;
    height = size.height;
    std::vector<ExrChannel> out;
    for (auto it = file.header().channels().begin(); it != file.header().channels().end(); ++it)
      out.push_back({it.name(), std::vector<float>(static_cast<std::size_t>(width) * static_cast<std::size_t>(height))});
    Imf::FrameBuffer fb;
    for (ExrChannel& c : out)
      fb.insert(c.name, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(c.pixels.data()), sizeof(float),
                                   sizeof(float) * static_cast<std::size_t>(width)));
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    return out;
  } catch (const DataError&) {
    throw;
  } catch (const std::exception& e) {  // missing, truncated, not an EXR: bad input (exit 2)
    throw DataError(fmt::format("{}: cannot read the EXR image: {}", path.string(), e.what()));
  }
}

namespace {
// The one writer of both entry points (the channels by reference: no copy of the pixels).
void write_channels(const std::filesystem::path& path, int width, int height, std::span<const ExrChannel> floats,
                    std::span<const ExrUintChannel> uints, const ExrAttributes& attributes,
                    ExrCompression compression, ExrThreads threads = ExrThreads::Pool) {
  const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  try {
    Imf::Header header(width, height);
    header.compression() = compression == ExrCompression::None  ? Imf::NO_COMPRESSION
                           : compression == ExrCompression::Rle ? Imf::RLE_COMPRESSION
                           : compression == ExrCompression::Piz ? Imf::PIZ_COMPRESSION
                                                                : Imf::ZIP_COMPRESSION;
    for (const auto& [name, value] : attributes.strings) header.insert(name, Imf::StringAttribute(value));
    for (const auto& [name, value] : attributes.doubles) header.insert(name, Imf::DoubleAttribute(value));
    for (const auto& [name, v] : attributes.vectors)
      header.insert(name, Imf::V3dAttribute(Imath::V3d(v[0], v[1], v[2])));
    Imf::FrameBuffer fb;
    for (const ExrChannel& c : floats) {
      if (c.pixels.size() != n)
        throw std::logic_error(fmt::format("EXR channel {} has {} pixels for {}×{}", c.name, c.pixels.size(), width, height));
      header.channels().insert(c.name, Imf::Channel(Imf::FLOAT));
      fb.insert(c.name, Imf::Slice(Imf::FLOAT, const_cast<char*>(reinterpret_cast<const char*>(c.pixels.data())),
                                   sizeof(float), sizeof(float) * static_cast<std::size_t>(width)));
    }
    for (const ExrUintChannel& c : uints) {
      if (c.pixels.size() != n)
        throw std::logic_error(fmt::format("EXR channel {} has {} pixels for {}×{}", c.name, c.pixels.size(), width, height));
      header.channels().insert(c.name, Imf::Channel(Imf::UINT));
      fb.insert(c.name, Imf::Slice(Imf::UINT, const_cast<char*>(reinterpret_cast<const char*>(c.pixels.data())),
                                   sizeof(std::uint32_t), sizeof(std::uint32_t) * static_cast<std::size_t>(width)));
    }
    CheckedOStream stream(path);
    {
      // Compression runs per block of lines on the threads polrig may use (--threads), or on
      // this thread alone; the file is the same for any count (its blocks are written in line order).
      Imf::OutputFile file(stream, header, use_exr_threads(threads));
      file.setFrameBuffer(fb);
      file.writePixels(height);
    }
    stream.close();
  } catch (const std::logic_error&) {
    throw;
  } catch (const std::exception& e) {
    throw std::runtime_error(fmt::format("{}: cannot write the EXR image: {}", path.string(), e.what()));
  }
}
}  // namespace

void write_exr(const std::filesystem::path& path, int width, int height,
               const std::vector<ExrChannel>& channels, ExrCompression compression) {
  write_channels(path, width, height, channels, {}, {}, compression);
}

void write_exr_image(const std::filesystem::path& path, const ExrImage& image, ExrCompression compression,
                     ExrThreads threads) {
  write_channels(path, image.width, image.height, image.floats, image.uints, image.attributes, compression, threads);
}

namespace {
// Rows [first_row, first_row + rows) of the image; rows < 0: to the bottom.
ExrImage read_rows(const std::filesystem::path& path, int first_row, int rows, int* image_height,
                   const std::optional<ExrSize>& expected, ExrThreads threads) {
  try {
    check_header_size(path, expected);
    Imf::InputFile file(path.string().c_str(), use_exr_threads(threads));
    const Imf::Header& h = file.header();
    const Imath::Box2i dw = h.dataWindow();
    const ExrSize size = claimed_size(path, dw, expected);
    const int height = size.height;
    if (image_height) *image_height = height;
    if (rows < 0) rows = height - first_row;
    if (first_row < 0 || rows < 1 || first_row > height - rows)
      throw std::runtime_error(fmt::format("rows {} to {} of an image of {} rows", first_row, first_row + rows - 1, height));
    ExrImage image;
    image.width = size.width;
    image.height = rows;
    const std::size_t n = static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height);
    const std::size_t row_floats = sizeof(float) * static_cast<std::size_t>(image.width);
    for (auto it = h.channels().begin(); it != h.channels().end(); ++it) {
      if (it.channel().type == Imf::UINT)
        image.uints.push_back({it.name(), std::vector<std::uint32_t>(n)});
      else
        image.floats.push_back({it.name(), std::vector<float>(n)});
    }
    Imf::FrameBuffer fb;
    // The slices' base is shifted to the data window's origin (which may not be (0, 0)) and the
    // first row read.
    const int y0 = dw.min.y + first_row;
    const std::ptrdiff_t origin = static_cast<std::ptrdiff_t>(dw.min.x) +
                                  static_cast<std::ptrdiff_t>(y0) * static_cast<std::ptrdiff_t>(image.width);
    for (ExrChannel& c : image.floats)
      fb.insert(c.name, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(c.pixels.data() - origin), sizeof(float), row_floats));
    for (ExrUintChannel& c : image.uints)
      fb.insert(c.name, Imf::Slice(Imf::UINT, reinterpret_cast<char*>(c.pixels.data() - origin), sizeof(std::uint32_t),
                                   sizeof(std::uint32_t) * static_cast<std::size_t>(image.width)));
    file.setFrameBuffer(fb);
    file.readPixels(y0, y0 + rows - 1);
    for (auto it = h.begin(); it != h.end(); ++it) {
      const Imf::Attribute& a = it.attribute();
      if (const auto* s = dynamic_cast<const Imf::StringAttribute*>(&a))
        image.attributes.strings.emplace_back(it.name(), s->value());
      else if (const auto* d = dynamic_cast<const Imf::DoubleAttribute*>(&a))
        image.attributes.doubles.emplace_back(it.name(), d->value());
      else if (const auto* f = dynamic_cast<const Imf::FloatAttribute*>(&a))
        image.attributes.doubles.emplace_back(it.name(), f->value());
      else if (const auto* i = dynamic_cast<const Imf::IntAttribute*>(&a))
        image.attributes.doubles.emplace_back(it.name(), i->value());
      else if (const auto* v = dynamic_cast<const Imf::V3dAttribute*>(&a))
        image.attributes.vectors.push_back({it.name(), {v->value().x, v->value().y, v->value().z}});
    }
    return image;
  } catch (const DataError&) {
    throw;
  } catch (const std::exception& e) {  // missing, truncated, not an EXR: bad input (exit 2)
    throw DataError(fmt::format("{}: cannot read the EXR image: {}", path.string(), e.what()));
  }
}
}  // namespace

ExrImage read_exr_image(const std::filesystem::path& path, std::optional<ExrSize> expected, ExrThreads threads) {
  return read_rows(path, 0, -1, nullptr, expected, threads);
}

ExrImage read_exr_rows(const std::filesystem::path& path, int first_row, int rows, int* image_height,
                       std::optional<ExrSize> expected, ExrThreads threads) {
  if (rows < 1)
    throw DataError(fmt::format("{}: cannot read the EXR image: {} rows requested", path.string(), rows));
  return read_rows(path, first_row, rows, image_height, expected, threads);
}

}  // namespace polrig
