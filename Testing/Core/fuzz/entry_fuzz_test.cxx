// SPDX-License-Identifier: BSD-3-Clause
// The core's entry-point fuzz harness (EntryFuzz.h) as a test: every file of
// the corpus, then a fixed number of inputs made from it by a seeded
// generator (random bytes, and corpus inputs with bytes changed, inserted,
// removed or cut). Built with AddressSanitizer and UndefinedBehaviorSanitizer
// where the compiler has them: any report aborts the test.
//
//   mcvol_entry_fuzz_test CORPUS_DIR [INPUTS [SEED]]
//
// scripts/sanitize.sh runs the same harness under libFuzzer (clang).
#include "EntryFuzz.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <dirent.h>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

namespace
{
std::vector<std::vector<uint8_t>> ReadCorpus(const std::string& dir)
{
  std::vector<std::string> names;
  if (DIR* d = opendir(dir.c_str()))
  {
    while (dirent* e = readdir(d))
    {
      if (e->d_name[0] != '.')
      {
        names.emplace_back(e->d_name);
      }
    }
    closedir(d);
  }
  std::sort(names.begin(), names.end());
  std::vector<std::vector<uint8_t>> corpus;
  for (const std::string& n : names)
  {
    std::ifstream f(dir + "/" + n, std::ios::binary);
    corpus.emplace_back(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
  }
  return corpus;
}
} // namespace

int main(int argc, char** argv)
{
  if (argc < 2)
  {
    std::fprintf(stderr, "usage: %s CORPUS_DIR [INPUTS [SEED]]\n", argv[0]);
    return 2;
  }
  const long inputs = argc > 2 ? std::atol(argv[2]) : 20000;
  const unsigned long long seed = argc > 3 ? std::strtoull(argv[3], nullptr, 10) : 1;
  const std::vector<std::vector<uint8_t>> corpus = ReadCorpus(argv[1]);
  if (corpus.empty())
  {
    std::fprintf(stderr, "no corpus files in %s\n", argv[1]);
    return 1;
  }
  for (const std::vector<uint8_t>& input : corpus)
  {
    mcvol::fuzz::RunOne(input.data(), input.size());
  }
  std::mt19937_64 rng(seed);
  std::vector<uint8_t> input;
  for (long i = 0; i < inputs; ++i)
  {
    if (rng() % 4 == 0)
    {
      input.resize(rng() % 600);
      for (uint8_t& b : input)
      {
        b = static_cast<uint8_t>(rng());
      }
    }
    else
    {
      input = corpus[rng() % corpus.size()];
      const int edits = 1 + int(rng() % 8);
      for (int e = 0; e < edits; ++e)
      {
        const size_t at = input.empty() ? 0 : rng() % input.size();
        switch (rng() % 4)
        {
          case 0:
            if (!input.empty())
            {
              input[at] = static_cast<uint8_t>(rng());
            }
            break;
          case 1:
            input.insert(input.begin() + long(at), static_cast<uint8_t>(rng()));
            break;
          case 2:
            if (!input.empty())
            {
              input.erase(input.begin() + long(at));
            }
            break;
          default:
            input.resize(at);
            break;
        }
      }
    }
    mcvol::fuzz::RunOne(input.data(), input.size());
  }
  std::printf("%zu corpus inputs and %ld generated inputs (seed %llu): no failure\n", corpus.size(), inputs, seed);
  return 0;
}
