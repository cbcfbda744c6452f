/// \file file_commit.hpp
/// Private to the result writer: a set of files written under temporary names and renamed into
/// place together, so that their predecessors are replaced all together or not at all.
#pragma once

#include "hssbem/io/temp_files.hpp"

#include <string>
#include <vector>

namespace hssbem::detail {

/// Files written under temporary names and renamed into place by commit().
/// - Each temporary file is created empty by add(), exclusively (O_CREAT | O_EXCL | O_NOFOLLOW,
///   `<final>.tmp.<host>.<pid>.<random>`, create_exclusive()) in the final name's directory; the
///   writers then open that existing file (HDF5's H5F_ACC_TRUNC, write_text_file without
///   O_CREAT), so that no planted file or symlink is ever written through. commit() renames only
///   the very file add() created (same device and inode, not a symlink). add() first sweeps the
///   temporaries that dead processes of this host left beside the final name.
/// - The temporary files are removed when the object dies uncommitted (an error) and when
///   SIGINT, SIGTERM or SIGHUP arrives before the commit; the signal then takes its course
///   (the previous handler, or the default action).
/// - commit() keeps each predecessor under `<final>.bak.<host>.<pid>.<random>` (a hard link)
///   while it renames the new files in, then syncs the directory (fsync); if a rename fails, the
///   files renamed so far are put back, so that every final name holds its predecessor again (or
///   nothing, if it had none), and it throws. A signal that arrives during the commit waits for
///   its end. Only SIGKILL or a power loss in the microseconds between two renames can leave a
///   mixed set (and the .bak files, which the next write beside them sweeps).
/// One set at a time per process (the signal handler has one registry).
class FileSetCommit {
public:
  /// `label` names the result in error messages ("cannot write output '<label>': ...").
  explicit FileSetCommit(std::string label);
  ~FileSetCommit();
  FileSetCommit(const FileSetCommit &)            = delete;
  FileSetCommit &operator=(const FileSetCommit &) = delete;

  /// Register `final_path`: create its temporary file (empty) and return its name.
  std::string add(const std::string &final_path);
  /// Rename every temporary file into place, all or none. Throws OutputError.
  void commit();

private:
  struct Entry {
    std::string   final_path, backup_path;
    ExclusiveFile temp;
    bool        had_predecessor = false, renamed = false;
  };
  void keep_predecessor(Entry &e);
  void roll_back();

  std::string        m_label;
  std::vector<Entry> m_entries;
  bool               m_committed = false;
};

/// Flushes `file` to disk (fsync), so that the rename that follows never exposes a file whose
/// data is still only in the page cache. Errors name `label`; throws OutputError.
void sync_file(const std::string &file, const std::string &label);

/// Writes `text` to `file`, which must exist (add() created it; a symlink is refused), and fsyncs
/// it, for the same reason as sync_file.
void write_text_file(const std::string &file, const std::string &text, const std::string &label);

} // namespace hssbem::detail
