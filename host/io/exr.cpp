// OpenEXR output of a render (linear RGB, depth, accumulation) and the reader the tests use.
#include "io/exr.hpp"

#include <ImfChannelList.h>
#include <ImfCompression.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>

#include <exception>

#include "core/error.hpp"
#include "io/atomic_file.hpp"

namespace mipnerf::io {
namespace {

constexpr const char* kChannelsAttribute = "mipnerf:channels";
constexpr const char* kChannelsDescription =
    "R,G,B: linear RGB (background composited, not premultiplied); Z: expected ray depth along the camera's "
    "optical axis, scene units; acc: accumulated opacity";

void require_size(const std::string& path, const std::vector<float>& values, size_t expected, const char* what) {
  if (values.size() != expected) {
    throw Error(path + ": the EXR image's " + what + " holds " + std::to_string(values.size()) +
                " values; its width and height need " + std::to_string(expected));
  }
}

// A float slice of an interleaved [height][width][stride] array starting at channel `offset`.
Imf::Slice float_slice(const float* data, size_t offset, size_t stride, uint32_t width) {
  return Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(const_cast<float*>(data + offset)), sizeof(float) * stride,
                    sizeof(float) * stride * width);
}

}  // namespace

void write_exr(const std::string& path, const ExrImage& image) {
  if (image.width == 0 || image.height == 0) throw Error(path + ": cannot write an empty EXR image (0 pixels)");
  const size_t pixels = static_cast<size_t>(image.width) * image.height;
  require_size(path, image.rgb, 3 * pixels, "rgb");
  if (!image.depth.empty()) require_size(path, image.depth, pixels, "depth");
  if (!image.acc.empty()) require_size(path, image.acc, pixels, "acc");

  Imf::Header header(static_cast<int>(image.width), static_cast<int>(image.height));
  header.compression() = Imf::ZIP_COMPRESSION;  // lossless
  Imf::FrameBuffer frame;
  const char* rgb_names[3] = {"R", "G", "B"};
  for (size_t c = 0; c < 3; ++c) {
    header.channels().insert(rgb_names[c], Imf::Channel(Imf::FLOAT));
    frame.insert(rgb_names[c], float_slice(image.rgb.data(), c, 3, image.width));
  }
  if (!image.depth.empty()) {
    header.channels().insert(kExrDepthChannel, Imf::Channel(Imf::FLOAT));
    frame.insert(kExrDepthChannel, float_slice(image.depth.data(), 0, 1, image.width));
  }
  if (!image.acc.empty()) {
    header.channels().insert(kExrAccChannel, Imf::Channel(Imf::FLOAT));
    frame.insert(kExrAccChannel, float_slice(image.acc.data(), 0, 1, image.width));
  }
  try {
    header.insert(kChannelsAttribute, Imf::StringAttribute(kChannelsDescription));
    for (const auto& [name, value] : image.attributes) {
      if (name == kChannelsAttribute) continue;
      if (header.find(name) != header.end()) {
        throw Error(path + ": EXR attribute '" + name + "' would replace a standard header attribute; rename it");
      }
      header.insert(name, Imf::StringAttribute(value));
    }
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error(path + ": bad EXR header attribute (" + e.what() + ")");
  }

  write_atomically(path, [&](const std::string& temporary) {
    try {
      Imf::OutputFile file(temporary.c_str(), header);
      file.setFrameBuffer(frame);
      file.writePixels(static_cast<int>(image.height));
    } catch (const std::exception& e) {
      throw Error(path + ": cannot write the EXR file (" + e.what() + ")");
    }
  });
}

ExrImage read_exr(const std::string& path) {
  try {
    Imf::InputFile file(path.c_str());
    const Imf::Header& header = file.header();
    const Imath::Box2i window = header.dataWindow();
    ExrImage image;
    image.width = static_cast<uint32_t>(window.max.x - window.min.x + 1);
    image.height = static_cast<uint32_t>(window.max.y - window.min.y + 1);
    const size_t pixels = static_cast<size_t>(image.width) * image.height;
    // Slices are addressed by absolute pixel coordinates: Slice::Make offsets the base by the data window.
    auto slice = [&](float* data, size_t stride) {
      return Imf::Slice::Make(Imf::FLOAT, data, window, sizeof(float) * stride, sizeof(float) * stride * image.width);
    };
    Imf::FrameBuffer frame;
    image.rgb.resize(3 * pixels);
    const char* rgb_names[3] = {"R", "G", "B"};
    for (size_t c = 0; c < 3; ++c) {
      if (!header.channels().findChannel(rgb_names[c])) {
        throw Error(path + ": the EXR file has no '" + rgb_names[c] + "' channel (R, G and B are required)");
      }
      frame.insert(rgb_names[c], slice(image.rgb.data() + c, 3));
    }
    if (header.channels().findChannel(kExrDepthChannel)) {
      image.depth.resize(pixels);
      frame.insert(kExrDepthChannel, slice(image.depth.data(), 1));
    }
    if (header.channels().findChannel(kExrAccChannel)) {
      image.acc.resize(pixels);
      frame.insert(kExrAccChannel, slice(image.acc.data(), 1));
    }
    file.setFrameBuffer(frame);
    file.readPixels(window.min.y, window.max.y);
    for (auto it = header.begin(); it != header.end(); ++it) {
      const auto* text = dynamic_cast<const Imf::StringAttribute*>(&it.attribute());
      if (text && std::string(it.name()) != kChannelsAttribute) image.attributes[it.name()] = text->value();
    }
    return image;
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    throw Error(path + ": cannot read the EXR file (" + e.what() + ")");
  }
}

}  // namespace mipnerf::io
