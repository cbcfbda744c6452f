/// \file temp_files.hpp
/// Safe names beside a file about to be replaced: temporaries created exclusively, stale ones of
/// dead processes swept, and the check that an output does not name an input. The result writer
/// (hdf5_output.hpp) uses them; so may any code that replaces a file.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <sys/types.h>

namespace hssbem {

/// A file this process created exclusively: its name and its identity (device, inode), so that
/// it can be recognised later whatever happens to the name meanwhile.
struct ExclusiveFile {
  std::string path;
  dev_t       device = 0;
  ino_t       inode  = 0;
};

/// Creates `<final_path>.<kind>.<host>.<pid>.<random>` in the directory of `final_path` with
/// open(O_CREAT | O_EXCL | O_NOFOLLOW), mode 0666 less the umask, and closes it (empty): no
/// existing file, link or symlink of that name is ever opened, and a name taken (by anyone) is
/// skipped for the next random one. `kind` is "tmp" or "bak" (a letters-only tag). The host and
/// process id in the name let a later run tell a leftover of a dead process
/// (sweep_stale_temporaries). Throws OutputError "cannot write output '<label>': ...".
ExclusiveFile create_exclusive(const std::string &final_path, const std::string &kind, const std::string &label);

/// A fresh name `<final_path>.<kind>.<host>.<pid>.<random>` (not created), for link(2), which
/// creates exclusively by itself.
std::string exclusive_name(const std::string &final_path, const std::string &kind);

/// True when `path` is still the regular file `f` (not replaced, not a symlink).
bool still_the_same_file(const ExclusiveFile &f);

/// Removes the temporaries of `final_path` (`<final_path>.tmp.*` and `.bak.*`; one call per
/// final name) that a process of this host left behind when it died (SIGKILL, power loss):
/// names of this scheme whose process id is not alive, that are regular files owned by this
/// user. Never those of a live process or of another host (a shared file system). Returns the
/// names removed.
std::vector<std::string> sweep_stale_temporaries(const std::string &final_path);

/// Flushes the directory of `path` to disk (fsync), so that a rename into it survives a power
/// loss. A file system that cannot sync directories (EINVAL) is let be. Throws OutputError.
void sync_directory(const std::string &path, const std::string &label);

/// Throws OutputError "cannot write output '<output>': it is the input file '<input>'" when the
/// directory entry `output` (or its XDMF sidecar's name), which the write would replace, is one of
/// `inputs` or the file one of them leads to: compared by device and inode (so `./mesh.off`, a
/// hard link or a path through another directory's symlink are all caught), not by the string.
/// Inputs that do not exist are skipped (their reader reports them).
void check_not_an_input(const std::string &output, const std::vector<std::string> &inputs);

namespace detail {
/// Tests only: while the object lives, the random part of the names comes from `source` (to
/// plant something on a name before it is created). Not thread-safe.
class TemporarySuffixForTests {
public:
  explicit TemporarySuffixForTests(std::function<std::string()> source);
  ~TemporarySuffixForTests();
  TemporarySuffixForTests(const TemporarySuffixForTests &)            = delete;
  TemporarySuffixForTests &operator=(const TemporarySuffixForTests &) = delete;
};
} // namespace detail

} // namespace hssbem
