#include "polrig/io/exr.h"

#include <stdexcept>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <fmt/format.h>

namespace polrig {

void write_exr(const std::filesystem::path& path, int width, int height,
               const std::vector<ExrChannel>& channels) {
  try {
    Imf::Header header(width, height);
    Imf::FrameBuffer fb;
    for (const ExrChannel& c : channels) {
      if (c.pixels.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height))
        throw std::logic_error(fmt::format("EXR channel {} has {} pixels for {}×{}", c.name,
                                           c.pixels.size(), width, height));
      header.channels().insert(c.name, Imf::Channel(Imf::FLOAT));
      fb.insert(c.name, Imf::Slice(Imf::FLOAT, const_cast<char*>(reinterpret_cast<const char*>(c.pixels.data())),
                                   sizeof(float), sizeof(float) * static_cast<std::size_t>(width)));
    }
    Imf::OutputFile file(path.string().c_str(), header);
    file.setFrameBuffer(fb);
    file.writePixels(height);
  } catch (const std::logic_error&) {
    throw;
  } catch (const std::exception& e) {
    throw std::runtime_error(fmt::format("{}: cannot write the EXR image: {}", path.string(), e.what()));
  }
}

std::vector<ExrChannel> read_exr(const std::filesystem::path& path, int& width, int& height) {
  try {
    Imf::InputFile file(path.string().c_str());
    const Imath::Box2i dw = file.header().dataWindow();
    width = dw.max.x - dw.min.x + 1;
    height = dw.max.y - dw.min.y + 1;
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
  } catch (const std::exception& e) {
    throw std::runtime_error(fmt::format("{}: cannot read the EXR image: {}", path.string(), e.what()));
  }
}

}  // namespace polrig
