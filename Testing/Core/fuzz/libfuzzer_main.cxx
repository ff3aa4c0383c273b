// SPDX-License-Identifier: BSD-3-Clause
// The core's entry-point harness (EntryFuzz.h) for libFuzzer: built by
// scripts/sanitize.sh with clang -fsanitize=fuzzer,address,undefined.
#include "EntryFuzz.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
  mcvol::fuzz::RunOne(data, size);
  return 0;
}
