/// \file xdmf.hpp
/// Private to the result writer: the XDMF sidecar text that points ParaView into the HDF5 file.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace hssbem::detail {

/// Element type of an HDF5 dataset, as XDMF names it.
enum class XdmfNumber { float64, int32, int8 };

/// One HDF5 dataset the sidecar refers to.
struct XdmfDataset {
  std::string path;                ///< absolute path inside the HDF5 file, e.g. /mesh/vertices
  std::vector<std::size_t> dims;   ///< dataset shape, slowest dimension first
  XdmfNumber number = XdmfNumber::float64;
};

/// A field shown in ParaView: AttributeType is "Scalar", "Vector" or "Matrix" (any number of
/// components), Center "Node" or "Cell".
struct XdmfAttribute {
  std::string name;
  std::string attribute_type;
  std::string center;
  XdmfDataset data;
};

/// A single triangle mesh with its fields, all stored in one HDF5 file.
struct XdmfGrid {
  std::string h5_name;   ///< how the sidecar names the HDF5 file: its basename, so the pair can move
  std::size_t num_vertices = 0;
  std::size_t num_triangles = 0;
  std::vector<XdmfAttribute> attributes;
  std::string name = "hssbem";  ///< the Grid's Name
  std::optional<double> time;   ///< its Time Value, for a grid in a temporal collection
  std::string vertices = "/mesh/vertices";   ///< the Geometry's dataset (num_vertices x 3)
  std::string triangles = "/mesh/triangles"; ///< the Topology's dataset (num_triangles x 3)
};

/// A temporal collection of grids (one per time step).
struct XdmfCollection {
  std::string name;
  std::vector<XdmfGrid> steps;
};

/// A rectilinear grid of points (3DRectMesh topology, VXVYVZ geometry: the coordinates along
/// each axis from HDF5 datasets), whose attributes are node-centred with dimensions
/// (points z, points y, points x, components).
struct XdmfRectGrid {
  std::string h5_name;
  std::string name;
  std::array<std::size_t, 3> points{}; ///< along x, y, z
  std::array<std::string, 3> axes;     ///< datasets of the coordinates along x, y, z
  std::vector<XdmfAttribute> attributes;
};

/// The XDMF 3 document for `grid`: one Uniform grid, Triangle topology, XYZ geometry; after it
/// the rectilinear grids `rect` and the triangle grids `more` (obstacles), if any.
std::string xdmf_document(const XdmfGrid &grid, const std::vector<XdmfRectGrid> &rect = {}, const std::vector<XdmfGrid> &more = {});

/// The XDMF 3 document of a sequence: the collections `before` (obstacles), then one Collection
/// grid "frames" of CollectionType "Temporal" holding `steps` (each a Uniform grid as in
/// xdmf_document, with its Time), which ParaView plays as time steps; the body's collection
/// last, where a reader that takes one collection (meshio's) looks.
std::string xdmf_temporal_document(const std::vector<XdmfGrid> &steps, const std::vector<XdmfCollection> &before = {});

/// `text` with the five XML special characters replaced by entities.
std::string xml_escape(const std::string &text);

} // namespace hssbem::detail
