// GoogleTest main for tests that need PETSc/MPI: a failure on any rank fails every rank, and only
// rank 0 prints.
//
// Assertions are collective-safe: a fatal failure (an ASSERT_*, or an exception out of a test) on
// one rank returns from the test on that rank only, while the others go on into the test's next
// collective call and would wait there until the test's time-out. So a fatal failure prints its
// message with the rank and ends the whole job at once (MPI_Abort, exit status 1). A non-fatal
// one (EXPECT_*) lets the test go on; the ranks' results are combined at the end.
#include "hssbem/petsc/log.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>

namespace {

class AbortOnFatalFailure : public ::testing::EmptyTestEventListener {
public:
  explicit AbortOnFatalFailure(int rank) : m_rank(rank) {}
  void OnTestPartResult(const ::testing::TestPartResult &r) override
  {
    if (!r.fatally_failed()) return;
    const ::testing::TestInfo *t = ::testing::UnitTest::GetInstance()->current_test_info();
    std::fprintf(stderr, "[rank %d] fatal failure in %s.%s at %s:%d:\n%s\n[rank %d] aborting every rank (a failure on one rank would leave the others waiting in a collective call)\n", m_rank,
                 t ? t->test_suite_name() : "?", t ? t->name() : "?", r.file_name() ? r.file_name() : "?", r.line_number(), r.message(), m_rank);
    std::fflush(stderr);
    MPI_Abort(MPI_COMM_WORLD, 1);
  }

private:
  int m_rank;
};

} // namespace

int main(int argc, char **argv)
{
  ::testing::InitGoogleTest(&argc, argv);
  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscCall(HssbemInitializePackage());
  PetscMPIInt rank, size;
  PetscCallMPI(MPI_Comm_rank(PETSC_COMM_WORLD, &rank));
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  auto &listeners = ::testing::UnitTest::GetInstance()->listeners();
  if (rank != 0 && !getenv("HSSBEM_TEST_ALL_RANKS")) delete listeners.Release(listeners.default_result_printer());
  if (size > 1) listeners.Append(new AbortOnFatalFailure(rank));
  int local = RUN_ALL_TESTS(), global = 0;
  PetscCallMPI(MPI_Allreduce(&local, &global, 1, MPI_INT, MPI_MAX, PETSC_COMM_WORLD));
  PetscCall(PetscFinalize());
  return global;
}
