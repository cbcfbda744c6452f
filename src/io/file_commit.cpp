/// \file file_commit.cpp
/// All-or-nothing replacement of a set of files (see file_commit.hpp).
#include "file_commit.hpp"

#include "hssbem/core/fault.hpp"
#include "hssbem/io/hdf5_output.hpp"
#include "hssbem/io/temp_files.hpp"

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <system_error>

#include <fcntl.h>
#include <unistd.h>

namespace hssbem::detail {

namespace {

// --- what the signal handler may touch: fixed buffers, async-signal-safe calls only ---------

constexpr int         k_max_files = 8, k_max_path = 4096;
constexpr int         k_signals[] = {SIGINT, SIGTERM, SIGHUP};
char                  g_temp[k_max_files][k_max_path];
volatile sig_atomic_t g_ntemp      = 0;
volatile sig_atomic_t g_committing = 0; // a signal now waits for the commit's end
volatile sig_atomic_t g_pending    = 0;
struct sigaction      g_previous[sizeof(k_signals) / sizeof(k_signals[0])];
bool                  g_active = false;

void restore_handlers()
{
  for (std::size_t i = 0; i < sizeof(k_signals) / sizeof(k_signals[0]); ++i) sigaction(k_signals[i], &g_previous[i], nullptr);
}

void remove_temps_now()
{
  for (int i = 0; i < g_ntemp; ++i) unlink(g_temp[i]);
  g_ntemp = 0;
}

extern "C" void on_signal(int sig)
{
  if (g_committing) {
    g_pending = sig;
    return;
  }
  remove_temps_now();
  restore_handlers();
  raise(sig); // delivered when this handler returns, to the previous handler or the default action
}

void install_handlers()
{
  struct sigaction sa;
  std::memset(&sa, 0, sizeof(sa));
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  for (std::size_t i = 0; i < sizeof(k_signals) / sizeof(k_signals[0]); ++i) sigaction(k_signals[i], &sa, &g_previous[i]);
}

[[noreturn]] void fail_sys(const std::string &label, int err, const std::string &what)
{
  throw OutputError("cannot write output '" + label + "': " + what + ": " + std::system_category().message(err));
}

} // namespace

FileSetCommit::FileSetCommit(std::string label) : m_label(std::move(label))
{
  if (g_active) throw std::logic_error("FileSetCommit: one set of files at a time");
  g_active = true;
  g_ntemp  = 0;
  install_handlers();
}

FileSetCommit::~FileSetCommit()
{
  g_committing = 1;
  if (!m_committed) remove_temps_now();
  g_ntemp = 0;
  restore_handlers();
  g_committing = 0;
  g_active     = false;
  if (g_pending) {
    const int sig = g_pending;
    g_pending     = 0;
    raise(sig);
  }
}

std::string FileSetCommit::add(const std::string &final_path)
{
  if (g_ntemp >= k_max_files || final_path.size() + 64 >= static_cast<std::size_t>(k_max_path))
    throw OutputError("cannot write output '" + m_label + "': path too long or too many files");
  sweep_stale_temporaries(final_path); // leftovers of runs killed on this host
  // Signals wait while the file is created and registered: a handler must find every one.
  sigset_t block, previous;
  sigemptyset(&block);
  for (int sig : k_signals) sigaddset(&block, sig);
  sigprocmask(SIG_BLOCK, &block, &previous);
  Entry e;
  try {
    e.temp = create_exclusive(final_path, "tmp", m_label);
  } catch (...) {
    sigprocmask(SIG_SETMASK, &previous, nullptr);
    throw;
  }
  std::memcpy(g_temp[g_ntemp], e.temp.path.c_str(), e.temp.path.size() + 1);
  g_ntemp = g_ntemp + 1;
  sigprocmask(SIG_SETMASK, &previous, nullptr);
  e.final_path = final_path;
  m_entries.push_back(std::move(e));
  return m_entries.back().temp.path;
}

/// A hard link keeps the predecessor under a fresh backup name while the final name is replaced
/// (link(2) never follows or replaces what is at the new name: a name taken is skipped).
void FileSetCommit::keep_predecessor(Entry &e)
{
  for (int attempt = 0; attempt < 16; ++attempt) {
    e.backup_path = exclusive_name(e.final_path, "bak");
    if (::link(e.final_path.c_str(), e.backup_path.c_str()) == 0) {
      e.had_predecessor = true;
      return;
    }
    const int err = errno;
    if (err == ENOENT) return; // nothing to keep
    if (err != EEXIST) fail_sys(m_label, err, "cannot keep the earlier '" + e.final_path + "' under '" + e.backup_path + "'");
  }
  fail_sys(m_label, EEXIST, "cannot keep the earlier '" + e.final_path + "' under a backup name");
}

/// Put back what the failed commit replaced: each final name gets its predecessor again, or
/// loses the new file when it had none.
void FileSetCommit::roll_back()
{
  for (Entry &e : m_entries) {
    if (e.renamed) {
      if (e.had_predecessor) std::rename(e.backup_path.c_str(), e.final_path.c_str());
      else ::unlink(e.final_path.c_str());
    } else if (e.had_predecessor) {
      ::unlink(e.backup_path.c_str());
    }
  }
}

void FileSetCommit::commit()
{
  g_committing = 1; // signals wait for the end (the destructor delivers them)
  try {
    for (Entry &e : m_entries) keep_predecessor(e);
    for (std::size_t i = 0; i < m_entries.size(); ++i) {
      Entry &e = m_entries[i];
      if (i > 0) fault_point("Commit"); // tests: a failure between two renames
      if (!still_the_same_file(e.temp)) // replaced behind our back: never publish a stranger's file
        fail_sys(m_label, EEXIST, "the temporary file '" + e.temp.path + "' was replaced by another file or link");
      if (std::rename(e.temp.path.c_str(), e.final_path.c_str()) != 0) {
        const int err = errno;
        fail_sys(m_label, err, "cannot rename '" + e.temp.path + "' to '" + e.final_path + "'");
      }
      e.renamed = true;
    }
    for (std::size_t i = 0; i < m_entries.size(); ++i) // once per directory: the renames survive a power loss
      if (i == 0 || std::filesystem::path(m_entries[i].final_path).parent_path() != std::filesystem::path(m_entries[i - 1].final_path).parent_path())
        sync_directory(m_entries[i].final_path, m_label);
  } catch (...) {
    roll_back();
    throw; // the destructor removes the temporary files left
  }
  for (Entry &e : m_entries)
    if (e.had_predecessor) ::unlink(e.backup_path.c_str());
  m_committed = true;
  g_ntemp     = 0;
}

// --- writing the temporary files ------------------------------------------------------------

namespace {

/// write(2) may write less than asked; loops until all is out.
void write_all(int fd, const std::string &text, const std::string &file, const std::string &label)
{
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR)
      continue;
    if (n < 0) {
      const int err = errno;
      ::close(fd);
      fail_sys(label, err, "cannot write '" + file + "'");
    }
    done += static_cast<std::size_t>(n);
  }
}

} // namespace

void sync_file(const std::string &file, const std::string &label)
{
  const int fd = ::open(file.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    fail_sys(label, err, "cannot open '" + file + "' to sync it");
  }
  const int status = ::fsync(fd);
  const int err = errno;
  ::close(fd);
  if (status != 0)
    fail_sys(label, err, "cannot sync '" + file + "'");
}

void write_text_file(const std::string &file, const std::string &text, const std::string &label)
{
  const int fd = ::open(file.c_str(), O_WRONLY | O_TRUNC | O_NOFOLLOW | O_CLOEXEC); // created exclusively by FileSetCommit::add
  if (fd < 0) {
    const int err = errno;
    fail_sys(label, err, "cannot create '" + file + "'");
  }
  write_all(fd, text, file, label);
  if (::fsync(fd) != 0) {
    const int err = errno;
    ::close(fd);
    fail_sys(label, err, "cannot sync '" + file + "'");
  }
  if (::close(fd) != 0) {
    const int err = errno;
    fail_sys(label, err, "cannot close '" + file + "'");
  }
}

} // namespace hssbem::detail
