#pragma once
// OpenEXR output (and the readers the round-trip tests use): the per-vertex radiosity as a
// "vertex image", and rendered HDR images. OpenEXR itself stays inside io/exr.cpp.
//
// Vertex EXR layout: shading vertex k (VertexField order) is pixel (k mod W, k div W) of a
// W x H image, W = min(V, kVertexExrWidth), H = ceil(V / W); pixels past V are padding with
// every channel 0 except surface = -1. FLOAT channels: R, G, B (radiosity B, the units of the
// scene's emission E), P.x, P.y, P.z (position, scene units), N.x, N.y, N.z (unit normal),
// surface (surface index as an exact integer in a float). Header attributes: vertexCount
// (int), vertexLayout, units, settings, software (strings), surfaceNames (string vector,
// indexed by surface). ZIP compression, scanlines, increasing Y.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/render/render.hpp"
#include "geometry/render/vertex_field.hpp"

namespace lambert {

/// Width of the vertex EXR image for large vertex counts.
constexpr int kVertexExrWidth = 1024;

/// Descriptive header attributes written with an EXR.
struct ExrInfo {
  std::string units;                       ///< what the pixel values mean and their units
  std::string settings;                    ///< the settings that produced the data (one line)
  std::vector<std::string> surface_names;  ///< vertex EXR: surface index -> name
  /// Vertex EXR: names of the three value channels (radiosity R, G, B; `lambert heat`:
  /// temperature, heat_flux, radiosity).
  std::array<std::string, 3> value_channels{"R", "G", "B"};
};

/// The content of a vertex EXR as read back.
struct VertexExr {
  int width = 0;
  int height = 0;
  std::int64_t vertex_count = 0;  ///< the vertexCount attribute
  Eigen::MatrixX3d radiosity;     ///< vertex_count x 3 (the value channels, R, G, B by default)
  std::vector<Eigen::Vector3d> positions;
  std::vector<Eigen::Vector3d> normals;
  std::vector<std::int32_t> surface;
  ExrInfo info;
  std::string layout;  ///< the vertexLayout attribute
};

/// Writes the shading vertices and their values (see the layout above), atomically.
/// Throws IoError on failure.
void write_vertex_exr(const std::string& path, const VertexField& field, const ExrInfo& info);

/// Reads a vertex EXR written by write_vertex_exr, its values from `value_channels`. Throws
/// IoError if unreadable or if a channel or attribute is missing.
VertexExr read_vertex_exr(const std::string& path,
                          const std::array<std::string, 3>& value_channels = {"R", "G", "B"});

/// Writes a linear HDR image: FLOAT channels R, G, B (radiance) and A (coverage), with the
/// units and settings attributes, atomically. Throws IoError.
void write_image_exr(const std::string& path, const Image& image, const ExrInfo& info);

/// Reads an RGB(A) float/half EXR (A defaults to 1 when absent). Throws IoError.
Image read_image_exr(const std::string& path, ExrInfo* info = nullptr);

}  // namespace lambert
