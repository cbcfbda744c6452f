/// \file file_commit.cpp
/// All-or-nothing replacement of a set of files (see file_commit.hpp).
#include "file_commit.hpp"

#include "hssbem/core/fault.hpp"
#include "hssbem/io/hdf5_output.hpp"

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
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

std::string pid_suffix() { return std::to_string(static_cast<long long>(::getpid())); }

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
  Entry e;
  e.final_path  = final_path;
  e.temp_path   = final_path + ".tmp." + pid_suffix();
  e.backup_path = final_path + ".bak." + pid_suffix();
  if (g_ntemp >= k_max_files || e.temp_path.size() >= static_cast<std::size_t>(k_max_path))
    throw OutputError("cannot write output '" + m_label + "': path too long or too many files");
  std::memcpy(g_temp[g_ntemp], e.temp_path.c_str(), e.temp_path.size() + 1);
  g_ntemp = g_ntemp + 1; // registered before creation: a create that fails halfway may leave a file
  m_entries.push_back(std::move(e));
  return m_entries.back().temp_path;
}

/// A hard link keeps the predecessor under its backup name while the final name is replaced.
void FileSetCommit::keep_predecessor(Entry &e)
{
  ::unlink(e.backup_path.c_str());
  if (::link(e.final_path.c_str(), e.backup_path.c_str()) == 0) {
    e.had_predecessor = true;
    return;
  }
  const int err = errno;
  if (err == ENOENT) return; // nothing to keep
  fail_sys(m_label, err, "cannot keep the earlier '" + e.final_path + "' under '" + e.backup_path + "'");
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
      if (std::rename(e.temp_path.c_str(), e.final_path.c_str()) != 0) {
        const int err = errno;
        fail_sys(m_label, err, "cannot rename '" + e.temp_path + "' to '" + e.final_path + "'");
      }
      e.renamed = true;
    }
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
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
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
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
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
