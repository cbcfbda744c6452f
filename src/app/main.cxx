// The driver's one error path (see main.hpp).
#include "hssbem/app/main.hpp"

#include "hssbem/app/options.hpp"
#include "hssbem/app/run.hpp"
#include "hssbem/session/petsc_call.hpp"
#include "hssbem/petsc/log.h"

#include <chrono>
#include <cstring>
#include <cmath>
#include <cstdio>
#include <exception>
#include <new>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace hssbem {

namespace {

/// PETSc errors are returned to the caller, not printed, for the lifetime of the object.
class QuietPetscErrors {
public:
  explicit QuietPetscErrors(bool on) : m_on(on)
  {
    if (m_on) HssbemCallThrow(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  }
  ~QuietPetscErrors()
  {
    if (m_on) (void)PetscPopErrorHandler();
  }
  QuietPetscErrors(const QuietPetscErrors &)            = delete;
  QuietPetscErrors &operator=(const QuietPetscErrors &) = delete;

private:
  bool m_on;
};

/// The run itself; returns the error message, empty on success.
std::string run_and_catch(MPI_Comm comm, bool version, int *failed)
{
  *failed = 1;
  try {
    HssbemCallThrow(HssbemInitializePackage());
    if (version) print_version(comm);
    else run_driver(comm);
    *failed = 0;
    return "";
  } catch (const std::bad_alloc &) {
    return "out of memory (an allocation failed; a smaller problem, more memory, or -bem_mat_type h2 may help)";
  } catch (const std::exception &e) {
    return name_the_option(e.what());
  } catch (...) {
    return "unknown exception";
  }
}

/// Waits for the non-blocking request up to `seconds`; false on time-out.
bool wait_for(MPI_Request *req, double seconds)
{
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  int        done = 0;
  while (true) {
    if (MPI_Test(req, &done, MPI_STATUS_IGNORE) != MPI_SUCCESS) return false;
    if (done) return true;
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

void print_error(const std::string &message)
{
  std::fprintf(stderr, "hssbem: error: %s\n", message.c_str());
  std::fflush(stderr);
}

/// Every rank, after the run: agree on whether any rank failed (on `agree`, a communicator of
/// its own, so that the agreement never meets a collective call of the run still in flight), and
/// print the lowest failing rank's message on rank 0. A rank that the others do not join in time
/// is stuck in a collective call: print what is known and abort the job.
int finish(MPI_Comm agree, int failed, std::string message, double timeout)
{
  int         rank, size, key, lowest = 0, length = 0;
  MPI_Request req;

  MPI_Comm_rank(agree, &rank);
  MPI_Comm_size(agree, &size);
  key = failed ? rank : size;
  MPI_Iallreduce(&key, &lowest, 1, MPI_INT, MPI_MIN, agree, &req);
  if (!wait_for(&req, timeout)) {
    print_error(failed ? message + " (on rank " + std::to_string(rank) + "; the other ranks did not stop: aborting)"
                       : "rank " + std::to_string(rank) + " finished but another rank did not (aborting)");
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
  if (lowest == size) return 0;
  if (rank == lowest) length = (int)message.size();
  MPI_Bcast(&length, 1, MPI_INT, lowest, agree);
  message.resize((size_t)length);
  if (length > 0) MPI_Bcast(&message[0], length, MPI_CHAR, lowest, agree);
  if (rank == 0) print_error(message);
  return 1;
}

/// The values PETSc complains about when it cannot parse them.
std::string bad_value_in(const std::string &message)
{
  static const std::regex patterns[] = {std::regex("Input string (\\S+) has no (numeric|integer) value"), std::regex("Unknown logical value: (\\S+)")};
  std::smatch             m;
  for (const auto &p : patterns)
    if (std::regex_search(message, m, p)) return m[1];
  return "";
}

} // namespace

std::string name_the_option(const std::string &message)
{
  const std::string value = bad_value_in(message);
  char             *all   = nullptr;
  if (value.empty() || PetscOptionsGetAll(NULL, &all) != PETSC_SUCCESS || !all) return message;
  std::istringstream       in(all);
  std::vector<std::string> tokens;
  for (std::string t; in >> t;) tokens.push_back(t);
  (void)PetscFree(all);
  std::string keys;
  for (std::size_t i = 1; i < tokens.size(); ++i)
    if (tokens[i] == value && tokens[i - 1].size() > 1 && tokens[i - 1][0] == '-') keys += (keys.empty() ? "" : ", ") + tokens[i - 1];
  return keys.empty() ? message : "option " + keys + " " + value + ": " + message;
}

bool take_version_option(int *argc, char **argv)
{
  bool found = false;
  int  kept  = 1;
  for (int i = 1; i < *argc; ++i) {
    const bool v = !std::strcmp(argv[i], "-version") || !std::strcmp(argv[i], "--version");
    found = found || v;
    if (!v) argv[kept++] = argv[i];
  }
  *argc = kept;
  argv[kept] = nullptr;
  return found;
}

int driver_main(MPI_Comm comm, bool version)
{
  PetscBool traceback = PETSC_FALSE;
  double    timeout   = option_default::hssbem_error_timeout; // a bad value is reported with the default
  MPI_Comm  agree;
  int       failed = 0;

  if (MPI_Comm_dup(comm, &agree) != MPI_SUCCESS) return 1;
  (void)PetscOptionsGetBool(NULL, NULL, "-hssbem_traceback", &traceback, NULL);
  std::string message;
  try {
    const QuietPetscErrors quiet(!traceback);
    try { // every rank reads the same value, so every rank fails here or none
      timeout = read_error_timeout();
      message = run_and_catch(comm, version, &failed);
    } catch (const std::exception &e) {
      failed  = 1;
      message = name_the_option(e.what());
    }
  } catch (const std::exception &e) { // the error handler itself could not be set
    failed  = 1;
    message = e.what();
  }
  const int status = finish(agree, failed, message, (double)timeout);
  MPI_Comm_free(&agree);
  return status;
}

} // namespace hssbem
