// SPDX-License-Identifier: BSD-3-Clause
// main() of the core tests: GoogleTest, plus the skip rule of the GPU runs.
// With MCVOL_TEST_BACKEND=cuda (or for tests that need a device) and no
// usable CUDA device, the program prints why and exits with 125, which CTest
// reports as skipped (SKIP_RETURN_CODE).
#include "mcvol/Renderer.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#ifndef MCVOL_TEST_NEEDS_CUDA
#define MCVOL_TEST_NEEDS_CUDA 0
#endif

int main(int argc, char** argv)
{
  testing::InitGoogleTest(&argc, argv);
  bool listing = false;
  for (int i = 1; i < argc; ++i)
  {
    listing = listing || std::strncmp(argv[i], "--gtest_list_tests", 18) == 0;
  }
  const char* env = std::getenv("MCVOL_TEST_BACKEND");
  const bool wantsCuda = MCVOL_TEST_NEEDS_CUDA || (env && std::string(env) == "cuda");
  std::string why;
  if (wantsCuda && !listing && !mcvol::Renderer::cudaAvailable(&why))
  {
    std::printf("SKIPPED: these tests need a CUDA device: %s\n", why.c_str());
    return 125;
  }
  return RUN_ALL_TESTS();
}
