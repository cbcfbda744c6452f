// The PETSc environment of a call from Python (see bind.hpp).
#include "bind.hpp"

#include "hssbem/session/petsc_call.hpp"

namespace hssbem::py_module {

CallEnvironment::CallEnvironment(const OptionList &options)
{
  HssbemCallThrow(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  m_quiet = true;
  try {
    HssbemCallThrow(PetscOptionsCreate(&m_options));
    for (const auto &[name, value] : options) HssbemCallThrow(PetscOptionsSetValue(m_options, ("-" + name).c_str(), value ? value->c_str() : NULL));
    HssbemCallThrow(PetscOptionsPush(m_options));
    m_pushed = true;
  } catch (...) {
    if (m_options) (void)PetscOptionsDestroy(&m_options);
    (void)PetscPopErrorHandler();
    throw;
  }
}

CallEnvironment::~CallEnvironment()
{
  if (m_pushed) (void)PetscOptionsPop();
  if (m_options) (void)PetscOptionsDestroy(&m_options);
  if (m_quiet) (void)PetscPopErrorHandler();
}

MPI_Comm comm_of(const std::optional<long long> &fortran_handle)
{
  if (!fortran_handle) return PETSC_COMM_WORLD;
  const MPI_Comm comm = MPI_Comm_f2c(static_cast<MPI_Fint>(*fortran_handle));
  if (comm == MPI_COMM_NULL) throw std::invalid_argument("comm: MPI_COMM_NULL is no communicator to solve on");
  return comm;
}

} // namespace hssbem::py_module
