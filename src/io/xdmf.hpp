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
  int column = -1;                 ///< ≥ 0: only this column of the last dimension (a HyperSlab)
};

/// A field shown in ParaView: AttributeType is "Scalar" or "Vector", Center "Node" or "Cell".
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

/// The XDMF 3 document for `grid`: one Uniform grid, Triangle topology, XYZ geometry; and after
/// it the rectilinear grids `rect`, if any.
std::string xdmf_document(const XdmfGrid &grid, const std::vector<XdmfRectGrid> &rect = {});

/// The XDMF 3 document of a sequence: one Collection grid of CollectionType "Temporal" holding
/// `steps` (each a Uniform grid as in xdmf_document, with its Time), which ParaView plays as
/// time steps.
std::string xdmf_temporal_document(const std::vector<XdmfGrid> &steps);

/// `text` with the five XML special characters replaced by entities.
std::string xml_escape(const std::string &text);

} // namespace hssbem::detail
