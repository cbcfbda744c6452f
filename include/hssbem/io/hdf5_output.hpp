/// \file hdf5_output.hpp
/// Result files: HDF5 with a ParaView-readable XDMF sidecar, written atomically: at once
/// (write_result) or frame by frame for a scene (FrameWriter).
#pragma once

#include "hssbem/core/geometry.hpp"

#include <mpi.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace hssbem {

class OutputError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

/// The stress fields of the surface (a solve's, or one frame's), in mesh vertex order; Voigt
/// order xx, yy, zz, yz, xz, xy. Empty: not written.
struct StressFields {
  std::vector<Voigt> stress;               ///< nv x 6 (mean over a vertex's dof nodes)
  std::vector<double> von_mises;           ///< nv
  std::vector<Vec3> principal;             ///< nv x 3, largest first
  std::vector<std::array<Voigt, 3>> corner; ///< nt x 3 x 6: triangle t at its corner c (empty in frames)
};

/// Displacement and stress on a regular grid of interior points (/interior/grid): points per
/// axis n = (nx, ny, nz), point (i, j, k) at origin + (i, j, k) * spacing, stored [k][j][i]
/// (x fastest), NaN where the point lies outside the body.
struct InteriorGridData {
  Vec3 origin{}, spacing{};
  std::array<int, 3> points{};
  std::vector<Vec3> displacement;
  std::vector<Voigt> stress;
  std::vector<double> von_mises;
  std::vector<int> inside; ///< 1 inside the body (or on its surface), 0 outside
  std::size_t size() const { return static_cast<std::size_t>(points[0]) * points[1] * points[2]; }
  bool empty() const { return displacement.empty(); }
};

/// A contact's results (contact/), in mesh vertex order: /contact (or /frames/<i>/contact).
struct ContactData {
  std::vector<double> pressure;        ///< /contact/pressure (nv): normal contact traction, >= 0
  std::vector<double> gap;             ///< /contact/gap (nv): NaN where a vertex faces nothing within reach
  std::vector<std::int8_t> status;     ///< /contact/status (nv int8): 0 free, 1 stick, 2 slip
  std::map<std::string, Vec3> forces;  ///< /contact/forces/<obstacle> and /contact/forces/body_<k> (3 each)
  /// per body that contact alone holds (its number k): /contact/bodies/<k>/translation (of its
  /// centroid) and /contact/bodies/<k>/rotation (the rotation vector about it, radians), 3 each
  std::map<int, std::array<Vec3, 2>> body_motion;
  long long iterations = 0;            ///< attribute of /contact
  long long active_vertices = 0;       ///< attribute of /contact
  bool present() const { return !pressure.empty(); }
};

/// A rigid obstacle's surface, to draw it beside the bodies (contact/obstacle.hpp:
/// obstacle_surface): /obstacles/<name>.
struct ObstacleSurface {
  std::string name;                          ///< the obstacle's name, an HDF5 link name (no '/' or ':', not "." or "..", no control character)
  std::string shape;                         ///< attribute `shape` of /obstacles/<name>: "plane" (a patch of it around the bodies), "sphere" (triangulated) or "mesh"
  std::vector<Vec3> vertices;                ///< /obstacles/<name>/vertices (n x 3): where it is (a single solve) or its base position (a scene)
  std::vector<std::array<int, 3>> triangles; ///< /obstacles/<name>/triangles (m x 3 int32), facing the bodies
};

/// Everything a result file holds, all arrays in mesh vertex order (whole on every rank that
/// writes: see the collective write_result).
struct ResultData {
  std::vector<Vec3> vertices;
  std::vector<std::array<int, 3>> triangles;
  std::vector<int> triangle_region;                 ///< /mesh/triangle_region
  std::vector<Vec3> displacement;                   ///< /fields/displacement
  std::vector<Vec3> traction;                       ///< /fields/traction (mean over double nodes)
  std::vector<std::array<Vec3, 3>> traction_corner; ///< /fields/traction_corner (nt x 3 x 3)
  std::vector<std::array<bool, 3>> displacement_prescribed; ///< /bc/displacement_prescribed (0/1)
  std::vector<int> sharp_vertex;                    ///< /mesh/sharp_vertex (0/1): double nodes
  std::map<std::string, Vec3> reactions;            ///< /reactions/<region>: integral of traction
  std::vector<Vec3> interior_points;                ///< /interior/points
  std::vector<Vec3> interior_displacement;          ///< /interior/displacement
  StressFields stress;                              ///< /fields/{stress, von_mises, principal_stress, stress_corner}
  std::vector<Voigt> interior_stress;               ///< /interior/stress (m x 6)
  std::vector<double> interior_von_mises;           ///< /interior/von_mises
  InteriorGridData interior_grid;                   ///< /interior/grid/...
  std::map<std::string, double> attributes_real;    ///< root attributes (E, nu, residual, ...)
  std::map<std::string, long long> attributes_int;  ///< root attributes (iterations, ranks, ...)
  std::map<std::string, std::string> attributes_str;///< root attributes (solver, version, ...)
  std::map<std::string, double> timings;            ///< /timings attributes, seconds per phase
  std::map<std::string, double> options_real;       ///< /options attributes: the options the run used, named without the dash
  std::map<std::string, long long> options_int;     ///< (integers, and booleans as 0 or 1)
  std::map<std::string, std::string> options_str;   ///< (names and texts)
  std::vector<std::string> input_files;             ///< not written: the run's inputs, which the result may not replace
  ContactData contact;                              ///< /contact, when present (the same on every rank)
  std::vector<ObstacleSurface> obstacles;           ///< /obstacles/<name>/{vertices, triangles}, when present
};

/// Check that `path` can be written (directory exists and is writable) before any work is done.
/// Also refused: a path that is a directory, or whose sidecar name is one; a `.xdmf` path (it
/// would be its own sidecar); a file name containing ':' (XDMF cannot refer to it); a path (or
/// sidecar) that is one of the `inputs` (check_not_an_input(): by device and inode).
/// Throws OutputError "cannot write output '<path>': <reason>".
void check_output_path(const std::string &path, const std::vector<std::string> &inputs = {});

/// Write `path` (HDF5) and `path` with extension .xdmf beside it (refused when either names one of
/// data.input_files). Both are written under temporary names created exclusively
/// (`<name>.tmp.<host>.<pid>.<random>`, temp_files.hpp; stale ones of dead processes are swept
/// first) and renamed into place together when complete, the directory then synced: the earlier pair is
/// replaced whole or not at all (a failed second rename puts the first back), a crash never
/// leaves a file that looks complete, and SIGINT/SIGTERM/SIGHUP during the write remove the
/// temporary files before the signal takes its course.
/// Layout: /mesh/{vertices, triangles, triangle_region, sharp_vertex}, /fields/{displacement,
/// traction, traction_corner}, /bc/displacement_prescribed, /reactions/<region>,
/// /interior/{points, displacement}, /contact/{pressure, gap, status, forces/<name>} with the
/// attributes iterations and active_vertices, /obstacles/<name>/{vertices, triangles} with the
/// attribute shape, root attributes, /timings attributes; empty optional arrays are skipped.
/// The sidecar shows the contact's pressure and status, and each obstacle as a grid of its own
/// after the body's. Arrays that are not empty must have one entry per vertex (triangle), and
/// every value written must be finite (the contact gap may be NaN: no obstacle within reach;
/// the interior grid's fields are NaN outside the body).
/// Throws OutputError; on error no temporary file is left and an existing result is untouched.
void write_result(const std::string &path, const ResultData &data);

/// write_result, collective over `comm`: every rank passes the whole `data` (arrays of the same
/// sizes on all ranks) and the file is written once, with HDF5's MPI-IO driver: each rank writes
/// its own contiguous block of rows of every dataset (the rows split evenly in rank order), the
/// ranks create groups, datasets and attributes together, and the attributes, timings and
/// reactions written are rank 0's. Rank 0 checks `path`, creates the temporary files (its host
/// and process id in their names) and the signal handling, and renames the pair into place once every rank has
/// closed the file and agreed that the write succeeded. Any failure, on any rank, throws the same
/// OutputError on every rank and leaves no file behind; an existing result stays untouched. With
/// one rank it is the serial write_result.
void write_result(MPI_Comm comm, const std::string &path, const ResultData &data);

/// One frame of a scene, all arrays in mesh vertex order.
struct FrameData {
  std::vector<Vec3> displacement;                           ///< nv x 3, required
  std::vector<Vec3> traction;                               ///< nv x 3, required
  std::vector<std::array<bool, 3>> displacement_prescribed; ///< nv x 3 or empty (not written)
  StressFields stress;                                      ///< stress, von_mises, principal_stress (nv each) or empty
  std::map<std::string, double> attributes_real;            ///< e.g. "seconds"
  std::map<std::string, long long> attributes_int;          ///< e.g. "iterations"
  std::map<std::string, std::string> attributes_str;        ///< e.g. "strategy"
  ContactData contact;                                      ///< /frames/<i>/contact, when present
  /// Per obstacle of the base (ResultData::obstacles, in its order), its surface's vertices as
  /// this frame places it: /frames/<i>/obstacles/<name>/vertices. Empty: not written (the
  /// sidecar then shows the base position).
  std::vector<std::vector<Vec3>> obstacle_vertices;
};

/// A result file written frame by frame: the frames of a scene are streamed into the temporary
/// file as they are solved, so memory does not grow with their number, and the file appears at
/// `path` (with its sidecar) only when commit() renames both into place, exactly as write_result
/// does; until then an earlier result at `path` stays as it was.
///
/// Layout: that of write_result (the base), plus for frame i = 0, 1, 2, ... (i in decimal):
///   /frames/<i>/displacement            nv x 3 float64
///   /frames/<i>/traction                nv x 3 float64
///   /frames/<i>/displacement_prescribed nv x 3 int8 (0/1), as /bc; only when given
///   /frames/<i>/contact/...             as /contact; only when given
///   /frames/<i>/obstacles/<name>/vertices  n x 3 float64: the base's obstacle <name> as the frame places it; only when given
///   attributes of /frames/<i>           FrameData::attributes_* (float64, int64, UTF-8)
/// /frames exists (maybe empty) from the start; /timings and the root attributes given to
/// commit() are written at the end.
///
/// Sidecar: the frames as one temporal collection (Grid CollectionType="Temporal"), one grid
/// per frame with Time = its index, the mesh from /mesh and the attributes displacement,
/// traction (and displacement_prescribed) from /frames/<i>, plus sharp_vertex and
/// triangle_region; before it, one temporal collection per obstacle of the base (its surface per
/// frame), so that a reader that takes one collection (meshio's) takes the body's, the last. The
/// base /fields are left out of it: ParaView draws every top-level grid of
/// the domain at every time step, so a static base grid would hide the frames it overlaps; they
/// stay in the HDF5 file. Committed without any frame, the sidecar is write_result's.
///
/// The temporary files are those of write_result (`<name>.tmp.<host>.<pid>.<random>`), removed on an error, by
/// the destructor when commit() was not reached, and on SIGINT/SIGTERM/SIGHUP meanwhile (the
/// handlers are installed for the writer's whole life). One writer (or write_result) at a time
/// per process. Errors throw OutputError naming `path`; after one that struck inside the file,
/// the writer refuses further appends and the commit.
class FrameWriter {
public:
  /// Checks `path` and `base` (as write_result does), creates the temporary HDF5 file and writes
  /// `base` into it, except base.timings, which commit() writes.
  FrameWriter(const std::string &path, const ResultData &base);
  /// Removes the temporary files unless commit() succeeded; an existing result stays untouched.
  ~FrameWriter();
  FrameWriter(const FrameWriter &) = delete;
  FrameWriter &operator=(const FrameWriter &) = delete;

  /// Appends frame `i`, which must be the number of frames appended so far, and flushes the file
  /// (H5Fflush). Throws OutputError for another index, arrays that are not one row per vertex
  /// (nothing is written then), or a failed write.
  void append(std::size_t i, const FrameData &frame);
  /// Number of frames appended so far.
  std::size_t num_frames() const;
  /// Writes /timings (base.timings, with `timings` winning on a shared phase) and the root
  /// attributes given here (e.g. "num_frames"; a name the base already used is an error), then
  /// the sidecar, and renames both files into place together. Throws OutputError.
  void commit(const std::map<std::string, double> &timings,
              const std::map<std::string, long long> &attributes_int = {},
              const std::map<std::string, double> &attributes_real = {},
              const std::map<std::string, std::string> &attributes_str = {});

private:
  struct Impl;
  std::unique_ptr<Impl> m_impl;
};

} // namespace hssbem
