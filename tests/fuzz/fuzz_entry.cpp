// One libFuzzer harness; HSSBEM_FUZZ_TARGET names its entry point in fuzz_targets.hpp.
#include "fuzz_targets.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t *data, std::size_t size)
{
  hssbem::fuzz::HSSBEM_FUZZ_TARGET(std::string(reinterpret_cast<const char *>(data), size));
  return 0;
}
