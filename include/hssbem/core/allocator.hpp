/// \file allocator.hpp
/// Give freed memory back to the system between phases.
///
/// SuperLU_DIST, which PETSc links, turns off glibc's returning of memory when it is loaded,
/// before main() runs: large blocks are no longer mapped on their own (mallopt(M_MMAP_MAX, 0)) and
/// the heap is never trimmed. Freed memory then stays resident, and a phase that frees much before
/// allocating anew adds to the process's peak what it freed. return_free_memory() gives the free
/// pages back wherever they lie in the heap (malloc_trim). The H² factorization calls it when its
/// levels are done (before the top is allocated) and when its frontier is spent: on 2 ranks of an
/// 80k sphere the largest rank's peak went from 1 533 to 1 472 MB (the levels had left 160-180 MB
/// free in the heap), and the resident size after the factorization from 1 614 to 1 350 MB.
/// Does nothing off glibc.
#pragma once

namespace hssbem {

void return_free_memory();

} // namespace hssbem
