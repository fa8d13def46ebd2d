#pragma once
// A property a fuzz target checks on the code under test. Unlike assert() it
// holds in every build type, and its message names the broken property, so a
// finding reads the same under libFuzzer and in the replay test.
#include <cstdio>
#include <cstdlib>

#define FUZZ_CHECK(cond)                                                                    \
  do {                                                                                      \
    if (!(cond)) {                                                                          \
      std::fprintf(stderr, "%s:%d: fuzz property failed: %s\n", __FILE__, __LINE__, #cond); \
      std::abort();                                                                         \
    }                                                                                       \
  } while (0)
