#include "io/exr.hpp"

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfIntAttribute.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfStringVectorAttribute.h>

#include <algorithm>
#include <exception>
#include <map>

#include "core/atomic_file.hpp"
#include "core/error.hpp"

namespace lambert {
namespace {

// Vertex channels in the order the layout lists them (the first three: the value channels,
// named by ExrInfo::value_channels).
const char* const kVertexChannels[] = {"R",   "G",   "B",   "P.x", "P.y",
                                       "P.z", "N.x", "N.y", "N.z", "surface"};
constexpr int kVertexChannelCount = 10;

std::vector<std::string> vertex_channels(const std::array<std::string, 3>& values) {
  std::vector<std::string> names(kVertexChannels, kVertexChannels + kVertexChannelCount);
  std::copy(values.begin(), values.end(), names.begin());
  return names;
}

const char* const kVertexLayoutText =
    "vertex k at pixel (k mod width, k div width); width = min(vertexCount, 1024); "
    "pixels past vertexCount are padding (surface = -1)";

// Float planes of one image, by channel name.
using Planes = std::map<std::string, std::vector<float>>;

void write_planes(const std::string& path, int width, int height, const Planes& planes,
                  const std::vector<std::string>& order, Imf::Header header) {
  for (const auto& name : order) header.channels().insert(name, Imf::Channel(Imf::FLOAT));
  header.compression() = Imf::ZIP_COMPRESSION;
  write_atomically(path, [&](const std::string& tmp) {
    try {
      Imf::FrameBuffer fb;
      for (const auto& name : order) {
        const auto& plane = planes.at(name);
        fb.insert(name, Imf::Slice(Imf::FLOAT,
                                   const_cast<char*>(reinterpret_cast<const char*>(plane.data())),
                                   sizeof(float), sizeof(float) * static_cast<size_t>(width)));
      }
      Imf::OutputFile file(tmp.c_str(), header);
      file.setFrameBuffer(fb);
      file.writePixels(height);
    } catch (const std::exception& e) {
      throw IoError(path + ": cannot write EXR: " + e.what());
    }
  });
}

// Reads the named float channels (missing ones filled with `fill`); returns the header.
Imf::Header read_planes(const std::string& path, const std::vector<std::string>& names,
                        const std::vector<std::string>& required, int& width, int& height,
                        Planes& planes, const std::map<std::string, float>& fill = {}) {
  try {
    Imf::InputFile file(path.c_str());
    const Imf::Header& header = file.header();
    const Imath::Box2i dw = header.dataWindow();
    width = dw.max.x - dw.min.x + 1;
    height = dw.max.y - dw.min.y + 1;
    for (const auto& name : required)
      if (!header.channels().findChannel(name))
        throw IoError(path + ": EXR has no channel '" + name + "'");
    Imf::FrameBuffer fb;
    const size_t count = static_cast<size_t>(width) * static_cast<size_t>(height);
    for (const auto& name : names) {
      auto& plane = planes[name];
      plane.assign(count, 0.0f);
      const auto f = fill.find(name);
      fb.insert(name, Imf::Slice::Make(Imf::FLOAT, plane.data(), dw, sizeof(float),
                                       sizeof(float) * static_cast<size_t>(width), 1, 1,
                                       f == fill.end() ? 0.0 : f->second));
    }
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    return header;
  } catch (const IoError&) {
    throw;
  } catch (const std::exception& e) {
    throw IoError(path + ": cannot read EXR: " + e.what());
  }
}

std::string string_attribute(const Imf::Header& h, const char* name) {
  const auto* a = h.findTypedAttribute<Imf::StringAttribute>(name);
  return a ? a->value() : std::string();
}

void add_info(Imf::Header& h, const ExrInfo& info) {
  h.insert("units", Imf::StringAttribute(info.units));
  h.insert("settings", Imf::StringAttribute(info.settings));
  h.insert("software", Imf::StringAttribute(std::string("lambert ") + LAMBERT_VERSION));
}

}  // namespace

void write_vertex_exr(const std::string& path, const VertexField& field, const ExrInfo& info) {
  const std::int64_t n = field.size();
  LAMBERT_CHECK(n > 0, "vertex EXR: no vertices");
  LAMBERT_CHECK(n < (std::int64_t{1} << 24),
                "vertex EXR: surface/vertex ids exceed float precision");
  LAMBERT_CHECK(field.values.rows() == n, "vertex EXR: values do not match the vertices");
  const int width = static_cast<int>(std::min<std::int64_t>(n, kVertexExrWidth));
  const int height = static_cast<int>((n + width - 1) / width);
  const size_t count = static_cast<size_t>(width) * static_cast<size_t>(height);
  Planes planes;
  const std::vector<std::string> order = vertex_channels(info.value_channels);
  for (const auto& name : order) planes[name].assign(count, 0.0f);
  auto& surface = planes["surface"];
  std::fill(surface.begin(), surface.end(), -1.0f);
  for (std::int64_t k = 0; k < n; ++k) {
    for (int c = 0; c < 3; ++c) {
      planes[order[c]][k] = static_cast<float>(field.values(k, c));
      planes[kVertexChannels[3 + c]][k] = static_cast<float>(field.positions[k][c]);
      planes[kVertexChannels[6 + c]][k] = static_cast<float>(field.normals[k][c]);
    }
    surface[k] = static_cast<float>(field.surface[k]);
  }
  Imf::Header header(width, height);
  add_info(header, info);
  header.insert("vertexCount", Imf::IntAttribute(static_cast<int>(n)));
  header.insert("vertexLayout", Imf::StringAttribute(kVertexLayoutText));
  header.insert("surfaceNames", Imf::StringVectorAttribute(info.surface_names));
  write_planes(path, width, height, planes, order, header);
}

VertexExr read_vertex_exr(const std::string& path,
                          const std::array<std::string, 3>& value_channels) {
  const std::vector<std::string> names = vertex_channels(value_channels);
  VertexExr out;
  Planes planes;
  const Imf::Header header = read_planes(path, names, names, out.width, out.height, planes);
  const auto* count = header.findTypedAttribute<Imf::IntAttribute>("vertexCount");
  if (!count) throw IoError(path + ": EXR has no vertexCount attribute (not a vertex EXR)");
  out.vertex_count = count->value();
  if (out.vertex_count < 0 || out.vertex_count > static_cast<std::int64_t>(out.width) * out.height)
    throw IoError(path + ": vertexCount " + std::to_string(out.vertex_count) +
                  " does not fit the image size");
  out.info.units = string_attribute(header, "units");
  out.info.settings = string_attribute(header, "settings");
  out.layout = string_attribute(header, "vertexLayout");
  if (const auto* s = header.findTypedAttribute<Imf::StringVectorAttribute>("surfaceNames"))
    out.info.surface_names = s->value();
  const auto n = out.vertex_count;
  out.radiosity.resize(n, 3);
  out.positions.resize(n);
  out.normals.resize(n);
  out.surface.resize(n);
  for (std::int64_t k = 0; k < n; ++k) {
    for (int c = 0; c < 3; ++c) {
      out.radiosity(k, c) = planes[names[c]][k];
      out.positions[k][c] = planes[kVertexChannels[3 + c]][k];
      out.normals[k][c] = planes[kVertexChannels[6 + c]][k];
    }
    out.surface[k] = static_cast<std::int32_t>(planes["surface"][k]);
  }
  return out;
}

void write_image_exr(const std::string& path, const Image& image, const ExrInfo& info) {
  const size_t count = static_cast<size_t>(image.width) * static_cast<size_t>(image.height);
  LAMBERT_CHECK(count > 0 && image.rgb.size() == 3 * count && image.alpha.size() == count,
                "image EXR: pixel buffers do not match the image size");
  Planes planes;
  const char* rgb[] = {"R", "G", "B"};
  for (int c = 0; c < 3; ++c) {
    auto& plane = planes[rgb[c]];
    plane.resize(count);
    for (size_t k = 0; k < count; ++k) plane[k] = image.rgb[3 * k + c];
  }
  planes["A"] = image.alpha;
  Imf::Header header(image.width, image.height);
  add_info(header, info);
  write_planes(path, image.width, image.height, planes, {"R", "G", "B", "A"}, header);
}

Image read_image_exr(const std::string& path, ExrInfo* info) {
  Image img;
  Planes planes;
  const Imf::Header header = read_planes(path, {"R", "G", "B", "A"}, {"R", "G", "B"}, img.width,
                                         img.height, planes, {{"A", 1.0f}});
  const size_t count = static_cast<size_t>(img.width) * static_cast<size_t>(img.height);
  img.rgb.resize(3 * count);
  const char* rgb[] = {"R", "G", "B"};
  for (int c = 0; c < 3; ++c)
    for (size_t k = 0; k < count; ++k) img.rgb[3 * k + c] = planes[rgb[c]][k];
  img.alpha = planes["A"];
  if (info) {
    info->units = string_attribute(header, "units");
    info->settings = string_attribute(header, "settings");
  }
  return img;
}

}  // namespace lambert
