/// \file frame_writer.cpp
/// FrameWriter: write_result's layout, with the frames of a scene streamed into the open
/// temporary file, and the same all-or-nothing rename at the end (see hdf5_output.hpp).
#include "hssbem/io/hdf5_output.hpp"

#include "file_commit.hpp"
#include "result_layout.hpp"

#include "hssbem/core/fault.hpp"

#include <optional>

namespace hssbem {

namespace {

using detail::fail_output;
using detail::H5Handle;
using detail::H5Writer;
using detail::XdmfGrid;

std::string frame_group(std::size_t i) { return "/frames/" + std::to_string(i); }

/// Everything is checked before the first byte of the frame is written, so that a refused frame
/// leaves the file as it was.
void check_frame(const std::string &path, std::size_t expected, std::size_t i, const FrameData &f,
                 std::size_t nv, const std::vector<ObstacleSurface> &obstacles)
{
  if (i != expected)
    fail_output(path, "frame " + std::to_string(i) + " appended after " + std::to_string(expected) +
                          " frames (frames go 0, 1, 2, ... in order)");
  const std::string g = frame_group(i);
  detail::check_size(path, g + "/displacement", f.displacement.size(), nv, "vertex", true);
  detail::check_size(path, g + "/traction", f.traction.size(), nv, "vertex", true);
  detail::check_size(path, g + "/displacement_prescribed", f.displacement_prescribed.size(), nv,
                     "vertex", false);
  detail::check_finite(path, g + "/displacement", f.displacement);
  detail::check_finite(path, g + "/traction", f.traction);
  detail::check_stress_sizes(path, g, f.stress, nv, 0); // no stress_corner in frames
  detail::check_contact(path, g + "/contact", f.contact, nv);
  detail::check_frame_obstacles(path, g, obstacles, f.obstacle_vertices);
}

void write_frame(H5Writer &w, std::size_t i, const FrameData &f, const std::vector<ObstacleSurface> &obstacles)
{
  const std::string name = frame_group(i);
  H5Handle g = w.group(name);
  detail::write_vec3s(w, g, name, "displacement", f.displacement);
  detail::write_vec3s(w, g, name, "traction", f.traction);
  if (!f.displacement_prescribed.empty())
    detail::write_mask(w, g, name, "displacement_prescribed", f.displacement_prescribed);
  detail::write_stress(w, g, name, f.stress);
  if (f.contact.present())
    detail::write_contact(w, name + "/contact", f.contact);
  detail::write_frame_obstacles(w, name, obstacles, f.obstacle_vertices);
  detail::write_attributes(w, g.get(), name, {f.attributes_real, f.attributes_int, f.attributes_str});
  w.end_group(g, name);
}

} // namespace

struct FrameWriter::Impl {
  Impl(const std::string &path_, const ResultData &base);

  /// The state every call but the constructor needs; throws once committed or broken.
  H5Writer &live(const char *call);
  /// The sidecar: a temporal collection of the frames, or write_result's grid if there is none.
  std::string sidecar() const;

  std::string path;
  XdmfGrid mesh_grid, result_grid;
  std::map<std::string, double> base_timings;
  std::size_t num_vertices;
  std::vector<bool> has_mask; ///< one entry per frame appended: displacement_prescribed written
  std::vector<StressFields> stress_shape; ///< per frame: which stress fields it holds (sizes only, no values)
  std::vector<bool> has_contact; ///< one entry per frame appended: contact written
  std::vector<ObstacleSurface> obstacles; ///< the base's (their surfaces at the base position)
  std::vector<bool> has_obstacles; ///< one entry per frame appended: its obstacles' places written
  bool broken = false, committed = false;
  // Destroyed in reverse order: the HDF5 file is closed before its temporary name is removed.
  std::optional<detail::FileSetCommit> files;
  std::string h5_tmp, xdmf_tmp;
  std::optional<H5Writer> h5;
};

FrameWriter::Impl::Impl(const std::string &path_, const ResultData &base)
    : path(path_), mesh_grid(detail::mesh_grid(path_, base)),
      result_grid(detail::result_grid(path_, base)), base_timings(base.timings),
      num_vertices(base.vertices.size()), obstacles(base.obstacles)
{
  files.emplace(path); // removes the temporary files on error and on SIGINT/SIGTERM/SIGHUP
  h5_tmp = files->add(path);
  xdmf_tmp = files->add(detail::xdmf_path(path));
  h5.emplace(h5_tmp, path);
  detail::write_result_groups(*h5, base, detail::metadata_of(base));
  H5Handle g = h5->group("/frames");
  h5->end_group(g, "/frames");
  h5->flush();
}

H5Writer &FrameWriter::Impl::live(const char *call)
{
  if (committed)
    fail_output(path, std::string(call) + " after commit(): the result is already in place");
  if (broken || !h5)
    fail_output(path, std::string(call) + " after an earlier write failed");
  return *h5;
}

std::string FrameWriter::Impl::sidecar() const
{
  if (has_mask.empty())
    return detail::xdmf_document(result_grid);
  std::vector<XdmfGrid> steps(has_mask.size(), mesh_grid);
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const std::string g = frame_group(i);
    std::vector<detail::XdmfAttribute> fields{
        detail::node_vectors("displacement", g + "/displacement", num_vertices, detail::XdmfNumber::float64),
        detail::node_vectors("traction", g + "/traction", num_vertices, detail::XdmfNumber::float64)};
    if (has_mask[i])
      fields.push_back(detail::node_vectors("displacement_prescribed", g + "/displacement_prescribed",
                                            num_vertices, detail::XdmfNumber::int8));
    const auto stress = detail::stress_attributes(g, stress_shape[i], num_vertices);
    fields.insert(fields.end(), stress.begin(), stress.end());
    if (has_contact[i])
      for (const detail::XdmfAttribute &a : detail::contact_attributes(g + "/contact", num_vertices))
        fields.push_back(a);
    steps[i].attributes.insert(steps[i].attributes.begin(), fields.begin(), fields.end());
    steps[i].name = "frame_" + std::to_string(i);
    steps[i].time = static_cast<double>(i);
  }
  return detail::xdmf_temporal_document(steps, detail::obstacle_collections(mesh_grid.h5_name, obstacles, has_obstacles));
}

FrameWriter::FrameWriter(const std::string &path, const ResultData &base)
{
  check_output_path(path, base.input_files);
  detail::validate_result(path, base);
  const detail::H5ErrorSilencer quiet;
  m_impl = std::make_unique<Impl>(path, base);
}

FrameWriter::~FrameWriter()
{
  const detail::H5ErrorSilencer quiet; // closing after an error may fail again: say nothing
  m_impl.reset();
}

void FrameWriter::append(std::size_t i, const FrameData &frame)
{
  H5Writer &w = m_impl->live("append");
  check_frame(m_impl->path, m_impl->has_mask.size(), i, frame, m_impl->num_vertices, m_impl->obstacles);
  const detail::H5ErrorSilencer quiet;
  m_impl->broken = true; // until the frame is whole: a half-written group cannot be retried
  write_frame(w, i, frame, m_impl->obstacles);
  w.flush();
  m_impl->has_mask.push_back(!frame.displacement_prescribed.empty());
  StressFields shape; // one entry each where the frame has the field: enough for the sidecar
  if (!frame.stress.stress.empty()) shape.stress.resize(1);
  if (!frame.stress.von_mises.empty()) shape.von_mises.resize(1);
  if (!frame.stress.principal.empty()) shape.principal.resize(1);
  m_impl->stress_shape.push_back(std::move(shape));
  m_impl->has_contact.push_back(frame.contact.present());
  m_impl->has_obstacles.push_back(!frame.obstacle_vertices.empty());
  m_impl->broken = false;
}

std::size_t FrameWriter::num_frames() const { return m_impl->has_mask.size(); }

void FrameWriter::commit(const std::map<std::string, double> &timings,
                         const std::map<std::string, long long> &attributes_int,
                         const std::map<std::string, double> &attributes_real,
                         const std::map<std::string, std::string> &attributes_str)
{
  Impl &m = *m_impl;
  H5Writer &w = m.live("commit");
  const detail::H5ErrorSilencer quiet;
  m.broken = true; // whatever fails from here on, the destructor cleans up
  std::map<std::string, double> all = timings;
  all.insert(m.base_timings.begin(), m.base_timings.end()); // keeps the values given here
  detail::write_timings(w, all);
  detail::write_attributes(w, w.root(), "/", {attributes_real, attributes_int, attributes_str});
  w.close();
  detail::sync_file(m.h5_tmp, m.path);
  detail::write_text_file(m.xdmf_tmp, m.sidecar(), m.path);
  fault_point("Write"); // tests: the temporary files are complete, nothing is renamed yet
  m.files->commit();     // the h5 first, as in write_result
  m.h5.reset();
  m.files.reset(); // gives the signal handlers back now, not when the writer dies
  m.broken = false;
  m.committed = true;
}

} // namespace hssbem
