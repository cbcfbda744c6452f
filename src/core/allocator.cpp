// Give freed memory back to the system (see allocator.hpp).
#include "hssbem/core/allocator.hpp"

#include <cstdlib> // defines __GLIBC__ on glibc

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace hssbem {

void return_free_memory()
{
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

} // namespace hssbem
