/// \file xdmf.cpp
/// XDMF sidecar text. Only the standard XDMF element and attribute names are used, because
/// ParaView's readers (Xdmf2 and Xdmf3) silently ignore anything they do not know.
#include "xdmf.hpp"

#include <iomanip>
#include <sstream>

namespace hssbem::detail {

namespace {

/// XDMF describes element types by a (NumberType, Precision) pair.
const char *number_type(XdmfNumber n)
{
  switch (n) {
  case XdmfNumber::float64: return R"(NumberType="Float" Precision="8")";
  case XdmfNumber::int32: return R"(NumberType="Int" Precision="4")";
  case XdmfNumber::int8: return R"(NumberType="Char" Precision="1")";
  }
  return "";
}

std::string dimensions(const std::vector<std::size_t> &dims)
{
  std::ostringstream out;
  for (std::size_t i = 0; i < dims.size(); ++i)
    out << (i ? " " : "") << dims[i];
  return out.str();
}

void put_data_item(std::ostream &out, const std::string &h5_name, const XdmfDataset &d,
                   const std::string &pad)
{
  out << pad << R"(<DataItem Format="HDF" Dimensions=")" << dimensions(d.dims) << "\" "
      << number_type(d.number) << ">" << xml_escape(h5_name) << ":" << xml_escape(d.path)
      << "</DataItem>\n";
}

void put_attribute(std::ostream &out, const std::string &h5_name, const XdmfAttribute &a,
                   const std::string &pad)
{
  out << pad << R"(<Attribute Name=")" << xml_escape(a.name) << R"(" AttributeType=")"
      << a.attribute_type << R"(" Center=")" << a.center << "\">\n";
  put_data_item(out, h5_name, a.data, pad + "  ");
  out << pad << "</Attribute>\n";
}

/// A Uniform grid whose <Grid> line is indented by `pad`.
void put_grid(std::ostream &out, const XdmfGrid &grid, const std::string &pad)
{
  const XdmfDataset triangles{grid.triangles, {grid.num_triangles, 3}, XdmfNumber::int32};
  const XdmfDataset vertices{grid.vertices, {grid.num_vertices, 3}, XdmfNumber::float64};
  const std::string in = pad + "  ";
  out << pad << "<Grid Name=\"" << xml_escape(grid.name) << "\" GridType=\"Uniform\">\n";
  if (grid.time) // 17 digits: a frame index past 10^6 stays exact
    out << in << "<Time Value=\"" << std::setprecision(17) << *grid.time << "\"/>\n";
  out << in << R"(<Topology TopologyType="Triangle" NumberOfElements=")" << grid.num_triangles
      << "\">\n";
  put_data_item(out, grid.h5_name, triangles, in + "  ");
  out << in << "</Topology>\n" << in << "<Geometry GeometryType=\"XYZ\">\n";
  put_data_item(out, grid.h5_name, vertices, in + "  ");
  out << in << "</Geometry>\n";
  for (const XdmfAttribute &a : grid.attributes)
    put_attribute(out, grid.h5_name, a, in);
  out << pad << "</Grid>\n";
}

/// A rectilinear grid whose <Grid> line is indented by `pad`.
void put_rect_grid(std::ostream &out, const XdmfRectGrid &grid, const std::string &pad)
{
  const std::string in = pad + "  ";
  out << pad << "<Grid Name=\"" << xml_escape(grid.name) << "\" GridType=\"Uniform\">\n";
  out << in << R"(<Topology TopologyType="3DRectMesh" Dimensions=")" << grid.points[2] << " "
      << grid.points[1] << " " << grid.points[0] << "\"/>\n";
  out << in << "<Geometry GeometryType=\"VXVYVZ\">\n";
  for (int a = 0; a < 3; ++a)
    put_data_item(out, grid.h5_name, {grid.axes[a], {grid.points[a]}, XdmfNumber::float64}, in + "  ");
  out << in << "</Geometry>\n";
  for (const XdmfAttribute &a : grid.attributes)
    put_attribute(out, grid.h5_name, a, in);
  out << pad << "</Grid>\n";
}

const char *k_head = "<?xml version=\"1.0\" ?>\n"
                     "<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
                     "<Xdmf Version=\"3.0\" xmlns:xi=\"http://www.w3.org/2001/XInclude\">\n"
                     "  <Domain>\n";
const char *k_tail = "  </Domain>\n"
                     "</Xdmf>\n";

} // namespace

std::string xml_escape(const std::string &text)
{
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
    case '&': out += "&amp;"; break;
    case '<': out += "&lt;"; break;
    case '>': out += "&gt;"; break;
    case '"': out += "&quot;"; break;
    case '\'': out += "&apos;"; break;
    default: out += c;
    }
  }
  return out;
}

std::string xdmf_document(const XdmfGrid &grid, const std::vector<XdmfRectGrid> &rect, const std::vector<XdmfGrid> &more)
{
  std::ostringstream out;
  out << k_head;
  put_grid(out, grid, "    ");
  for (const XdmfRectGrid &r : rect)
    put_rect_grid(out, r, "    ");
  for (const XdmfGrid &g : more)
    put_grid(out, g, "    ");
  out << k_tail;
  return out.str();
}

namespace {

void put_collection(std::ostream &out, const XdmfCollection &c)
{
  out << R"(    <Grid Name=")" << xml_escape(c.name) << R"(" GridType="Collection" CollectionType="Temporal">)" << "\n";
  for (const XdmfGrid &grid : c.steps)
    put_grid(out, grid, "      ");
  out << "    </Grid>\n";
}

} // namespace

std::string xdmf_temporal_document(const std::vector<XdmfGrid> &steps, const std::vector<XdmfCollection> &before)
{
  std::ostringstream out;
  out << k_head;
  for (const XdmfCollection &c : before)
    put_collection(out, c);
  put_collection(out, {"frames", steps});
  out << k_tail;
  return out.str();
}

} // namespace hssbem::detail
