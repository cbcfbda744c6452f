#!/usr/bin/env bash
# Install hssbem's build and test dependencies from Debian 12's packages (needs root or sudo) and
# make sure BLAS/LAPACK resolve to OpenBLAS (PETSc otherwise runs on the reference BLAS, ~10x slower).
set -euo pipefail

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi

packages=(
  build-essential cmake pkg-config          # compilers, build system
  petsc-dev libopenmpi-dev openmpi-bin      # PETSc 3.18 on Open MPI, mpiexec
  libopenblas-dev libmetis-dev              # BLAS/LAPACK (OpenBLAS), METIS
  libscalapack-openmpi-dev                  # ScaLAPACK (PETSc's): the H² top spread over the ranks
  libhdf5-openmpi-dev                       # HDF5 headers PETSc was built with
  libgtest-dev nlohmann-json3-dev           # unit tests, problem-file parser
  python3 python3-numpy python3-h5py        # CLI tests, benchmark scripts
  gmsh python3-gmsh                         # mesh generation (scripts/gen_meshes.py)
  python3-matplotlib                        # scripts/render.py (Agg PNGs; brings python3-pil for GIFs)
  python3-jsonschema                        # the problem file's schema (scripts/problem_schema.py, ctest problem_schema)
  python3-meshio                            # the CLI tests read the XDMF sidecar as another reader would
  python3-dev python3-pybind11              # the Python module hssbem (python/, docs/python.md)
  python3-petsc4py python3-mpi4py python3-pytest # its PETSc and MPI objects, its tests (tests/python/)
)

echo "install_deps: apt-get install ${#packages[@]} packages"
$SUDO apt-get update -q
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${packages[@]}"

arch=$(dpkg-architecture -qDEB_HOST_MULTIARCH 2>/dev/null || echo x86_64-linux-gnu)
for lib in libblas.so.3 liblapack.so.3; do
  name="${lib}-${arch}"
  query=$(update-alternatives --query "$name")
  current=$(sed -n 's/^Value: //p' <<<"$query")
  if [[ "$current" == */openblas*/* ]]; then
    echo "install_deps: $name -> $current (OpenBLAS)"
  else
    openblas=$(sed -n 's/^Alternative: \(.*openblas.*\)$/\1/p' <<<"$query" | head -n 1)
    [ -n "$openblas" ] || { echo "install_deps: no OpenBLAS alternative for $name" >&2; exit 1; }
    echo "install_deps: $name -> ${current:-none}; switching to $openblas"
    $SUDO update-alternatives --set "$name" "$openblas"
  fi
done
