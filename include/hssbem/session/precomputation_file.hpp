/// \file precomputation_file.hpp
/// A contact's precomputation (ContactPrecomputation: the dense reference of each body, its LU
/// factors and pivots and the kept columns of K₀′, and the columns of W computed so far) saved
/// to one file and loaded back instead of the set-up, for the same problem (docs/persistence.md).
///
/// The file (io/saved_file.hpp: a checksummed HDF5 file, written the safe way) keeps the
/// precomputation's Fingerprint beside it; a load compares it with the session's before it reads
/// anything else and refuses a file made for another problem with one line naming what differs.
/// Values (loads, prescribed displacements, obstacle poses) may differ: that is the point. The
/// frames after a load are the cold run's to the bit (the same factors, the same columns).
///
/// Layout (format 2): text attributes `fingerprint_*` (the Fingerprint's fields); arrays
/// `on_h2` (per body), `reference/*` (one body) or `body<b>/*` (several: CompositeReference),
/// each a DenseReferenceData (`pattern`, `lu`, `piv`, `K`, `kpos`, `H`, `G`, `Gn`, `scale_t`),
/// and `columns/order` with `columns/<k>/js`, `columns/<k>/values` for the k-th block of W's
/// columns. A contact's precomputation lives on one rank (rank 0's): the file is one rank's too.
#pragma once

#include "hssbem/io/saved_file.hpp"
#include "hssbem/session/contact_session.hpp"
#include "hssbem/session/scene_session.hpp"

#include <memory>
#include <string>
#include <vector>

namespace hssbem {

/// The format version the files are written in and the only one read (a change of layout
/// increments it; docs/persistence.md).
inline constexpr int kPrecomputationFormat = 2;

/// A Fingerprint as the text attributes `fingerprint_<field>` of a saved file, and back (any
/// precomputation's file: this one's, session/h2_file.hpp's). read_fingerprint() throws
/// SavedFileError for a missing or damaged field.
void write_fingerprint(SavedFileWriter &w, const Fingerprint &f);
Fingerprint read_fingerprint(const SavedFileReader &r);

/// Saves `session`'s precomputation (after set_up(), or after frames: the columns they added are
/// kept too) to `path`, which may not be one of `inputs`. Throws std::invalid_argument before
/// set-up or for an H² reference (not saved yet), OutputError when the file cannot be written.
void save_precomputation(const ContactSession &session, const std::string &path, const std::vector<std::string> &inputs = {});

/// Before a contact's set-up, on every rank: throws std::invalid_argument when its references
/// `mat_type` (reference_mat_type()) cannot be saved or loaded (only dense ones are, yet), the line
/// naming `option` as the face spells it ("-hssbem_save", "hssbem_load") and ending in `remedy`.
void check_contact_reference_saveable(const std::string &mat_type, const std::string &option, const std::string &remedy = "");

/// The precomputation saved in `path` for `session`'s problem, ready for session.adopt(). Throws
/// SavedFileError ("cannot load '<path>': ...") for a file that is not one, is damaged, or was
/// made for another problem (the first difference named: Fingerprint::difference()).
std::shared_ptr<ContactPrecomputation> load_precomputation(const ContactSession &session, const std::string &path);

/// A scene's precomputation (kind "scene precomputation", the same format): the fingerprint
/// (SceneSession::fingerprint()), `reference/*` (the DenseReferenceData of the reference pattern:
/// its LU, and H, G, Gn as the scene keeps them), `scene/W` (W's candidate columns, rows in
/// unknown order), `scene/Wp` (W_p, with pressure loads) and `scene/rates` (the cost model's
/// measured rates, so that `auto` chooses as the scene that saved them). Throws as the contact's.
void save_scene_precomputation(const SceneSession &session, const std::string &path, const std::vector<std::string> &inputs = {});
/// The parts of the scene precomputation saved in `path` for `session`'s problem, for
/// DenseScene's loading constructor (SceneSession::load()).
DenseScene::Saved load_scene_precomputation(const SceneSession &session, const std::string &path);

} // namespace hssbem
