/// \file temp_files.cpp
/// Exclusive temporary names, the sweep of dead processes' leftovers, directory sync and the
/// output-is-an-input check (see temp_files.hpp).
#include "hssbem/io/temp_files.hpp"

#include "hssbem/io/hdf5_output.hpp"

#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <random>
#include <system_error>

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

namespace hssbem {

namespace {

namespace fs = std::filesystem;

std::function<std::string()> g_suffix_for_tests;

[[noreturn]] void fail_sys(const std::string &label, int err, const std::string &what)
{
  throw OutputError("cannot write output '" + label + "': " + what + ": " + std::system_category().message(err));
}

/// This host's name with every character but letters, digits and '-' replaced by '-', so that
/// the name's fields stay separable by '.'.
std::string host_tag()
{
  char buf[256] = "";
  if (::gethostname(buf, sizeof(buf) - 1) != 0 || !buf[0]) return "host";
  std::string h(buf);
  for (char &c : h)
    if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-')) c = '-';
  return h;
}

std::string random_suffix()
{
  if (g_suffix_for_tests) return g_suffix_for_tests();
  static std::random_device rd; // getrandom(2) on Linux
  char buf[17];
  std::snprintf(buf, sizeof(buf), "%08x%08x", static_cast<unsigned>(rd()), static_cast<unsigned>(rd()));
  return buf;
}

fs::path directory_of(const std::string &path)
{
  const fs::path parent = fs::path(path).parent_path();
  return parent.empty() ? fs::path(".") : parent;
}

/// The process id in `name` when it is `<base>.<kind>.<host>.<pid>.<random>` for this host and
/// kind "tmp" or "bak"; -1 otherwise.
long long pid_in(const std::string &name, const std::string &base, const std::string &host)
{
  for (const char *kind : {".tmp.", ".bak."}) {
    const std::string head = base + kind + host + ".";
    if (name.compare(0, head.size(), head) != 0) continue;
    const std::string rest = name.substr(head.size()); // <pid>.<random>
    const std::size_t dot  = rest.find('.');
    if (dot == 0 || dot == std::string::npos || rest.find('.', dot + 1) != std::string::npos) return -1;
    long long pid = 0;
    for (std::size_t i = 0; i < dot; ++i) {
      if (rest[i] < '0' || rest[i] > '9' || pid > 1e12) return -1;
      pid = pid * 10 + (rest[i] - '0');
    }
    return pid;
  }
  return -1;
}

bool process_is_dead(long long pid)
{
  if (pid <= 0 || pid == static_cast<long long>(::getpid())) return false;
  return ::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH;
}

} // namespace

std::string exclusive_name(const std::string &final_path, const std::string &kind)
{
  return final_path + "." + kind + "." + host_tag() + "." + std::to_string(static_cast<long long>(::getpid())) + "." + random_suffix();
}

ExclusiveFile create_exclusive(const std::string &final_path, const std::string &kind, const std::string &label)
{
  constexpr int k_attempts = 16;
  int           err        = EEXIST;
  for (int attempt = 0; attempt < k_attempts && err == EEXIST; ++attempt) {
    const std::string name = exclusive_name(final_path, kind);
    const int         fd   = ::open(name.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
    if (fd < 0) {
      err = errno;
      continue;
    }
    struct stat st;
    const int   status = ::fstat(fd, &st);
    err                = errno;
    ::close(fd);
    if (status != 0) {
      ::unlink(name.c_str());
      fail_sys(label, err, "cannot inspect '" + name + "'");
    }
    return {name, st.st_dev, st.st_ino};
  }
  fail_sys(label, err, "cannot create a temporary file beside '" + final_path + "'");
}

bool still_the_same_file(const ExclusiveFile &f)
{
  struct stat st;
  return ::lstat(f.path.c_str(), &st) == 0 && S_ISREG(st.st_mode) && st.st_dev == f.device && st.st_ino == f.inode;
}

std::vector<std::string> sweep_stale_temporaries(const std::string &final_path)
{
  std::vector<std::string> removed;
  const fs::path           dir  = directory_of(final_path);
  const std::string        base = fs::path(final_path).filename().string(), host = host_tag();
  DIR                     *d    = ::opendir(dir.c_str());
  if (!d) return removed; // the writer's own checks report a directory it cannot use
  while (const dirent *e = ::readdir(d)) {
    const std::string name = e->d_name;
    if (!process_is_dead(pid_in(name, base, host))) continue;
    const std::string path = (dir / name).string();
    struct stat       st;
    if (::lstat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode) || st.st_uid != ::geteuid()) continue;
    if (::unlink(path.c_str()) == 0) removed.push_back(path);
  }
  ::closedir(d);
  return removed;
}

void sync_directory(const std::string &path, const std::string &label)
{
  const std::string dir = directory_of(path).string();
  const int         fd  = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) {
    const int err = errno;
    fail_sys(label, err, "cannot open directory '" + dir + "' to sync it");
  }
  const int status = ::fsync(fd);
  const int err    = errno;
  ::close(fd);
  if (status != 0 && err != EINVAL) fail_sys(label, err, "cannot sync directory '" + dir + "'");
}

void check_not_an_input(const std::string &output, const std::vector<std::string> &inputs)
{
  const std::string sidecar = fs::path(output).replace_extension(".xdmf").string();
  for (const std::string &out : {output, sidecar}) {
    struct stat o;
    if (::lstat(out.c_str(), &o) != 0) continue; // nothing there to replace
    for (const std::string &in : inputs) {
      struct stat target, link;
      const bool  same_target = ::stat(in.c_str(), &target) == 0 && target.st_dev == o.st_dev && target.st_ino == o.st_ino;
      const bool  same_link   = ::lstat(in.c_str(), &link) == 0 && link.st_dev == o.st_dev && link.st_ino == o.st_ino;
      if (same_target || same_link)
        throw OutputError("cannot write output '" + output + "': " + (out == output ? "it" : "its XDMF sidecar '" + out + "'") + " is the input file '" + in +
                          "', which the result would replace; choose another output name");
    }
  }
}

namespace detail {
TemporarySuffixForTests::TemporarySuffixForTests(std::function<std::string()> source) { g_suffix_for_tests = std::move(source); }
TemporarySuffixForTests::~TemporarySuffixForTests() { g_suffix_for_tests = nullptr; }
} // namespace detail

} // namespace hssbem
