/// \file file_commit.hpp
/// Private to the result writer: a set of files written under temporary names and renamed into
/// place together, so that their predecessors are replaced all together or not at all.
#pragma once

#include <string>
#include <vector>

namespace hssbem::detail {

/// Files written under temporary names `<final>.tmp.<pid>` and renamed into place by commit().
/// - The temporary files are removed when the object dies uncommitted (an error) and when
///   SIGINT, SIGTERM or SIGHUP arrives before the commit; the signal then takes its course
///   (the previous handler, or the default action).
/// - commit() keeps each predecessor under `<final>.bak.<pid>` (a hard link) while it renames the
///   new files in; if a rename fails, the files renamed so far are put back, so that every final
///   name holds its predecessor again (or nothing, if it had none), and it throws. A signal
///   that arrives during the commit waits for its end. Only SIGKILL or a power loss in the
///   microseconds between two renames can leave a mixed set (and the .bak files).
/// One set at a time per process (the signal handler has one registry).
class FileSetCommit {
public:
  /// `label` names the result in error messages ("cannot write output '<label>': ...").
  explicit FileSetCommit(std::string label);
  ~FileSetCommit();
  FileSetCommit(const FileSetCommit &)            = delete;
  FileSetCommit &operator=(const FileSetCommit &) = delete;

  /// Register `final_path`; returns the temporary name to write it under.
  std::string add(const std::string &final_path);
  /// Rename every temporary file into place, all or none. Throws OutputError.
  void commit();

private:
  struct Entry {
    std::string final_path, temp_path, backup_path;
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

/// Writes `text` to `file` and fsyncs it, for the same reason as sync_file.
void write_text_file(const std::string &file, const std::string &text, const std::string &label);

} // namespace hssbem::detail
