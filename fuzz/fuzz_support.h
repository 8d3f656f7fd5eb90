// Shared plumbing of the libFuzzer harnesses: a per-process scratch directory for readers
// that take a path, and the one rule for what counts as a finding.
//
// A reader may reject any input, but only with skycal::Error (its message names the file
// and field; that is the documented contract). Other std::exceptions (e.g. a
// nlohmann::json::type_error leaking out of a reader) are caught by the CLI's generic
// handler and exit 1, so they are not crashes; SKYCAL_FUZZ_STRICT=1 turns them into
// aborts to hunt them down, and SKYCAL_FUZZ_VERBOSE=1 prints every rejection.
// std::bad_alloc always aborts: a reader that allocates from a header's claims is a
// finding (bench/results/fuzz.md).
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <new>
#include <string>

#include "skycal/core/error.h"

namespace skycal::fuzz {

// A fresh directory under /dev/shm (memory; no disk writes per execution) or /tmp, made
// once per process and removed at exit.
inline const std::filesystem::path& ScratchDir() {
  static const std::filesystem::path dir = [] {
    const char* base = std::filesystem::is_directory("/dev/shm") ? "/dev/shm" : "/tmp";
    std::string tmpl = std::string(base) + "/skycal-fuzz-XXXXXX";
    if (!mkdtemp(tmpl.data())) {
      std::perror("skycal fuzz: mkdtemp");
      std::abort();
    }
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(ScratchDir(), ec);
    });
    return std::filesystem::path(tmpl);
  }();
  return dir;
}

// Writes the fuzz input to ScratchDir()/name and returns the path.
inline std::string WriteInput(const std::string& name, const uint8_t* data, size_t size) {
  const std::filesystem::path p = ScratchDir() / name;
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  if (!f) {
    std::perror("skycal fuzz: write input");
    std::abort();
  }
  return p.string();
}

// SKYCAL_FUZZ_VERBOSE=1: print each rejection (to see how far a reproducer gets).
inline bool Verbose() {
  static const bool verbose = [] {
    const char* s = std::getenv("SKYCAL_FUZZ_VERBOSE");
    return s && s[0] == '1';
  }();
  return verbose;
}

inline bool Strict() {
  static const bool strict = [] {
    const char* s = std::getenv("SKYCAL_FUZZ_STRICT");
    return s && s[0] == '1';
  }();
  return strict;
}

// Runs one reader call under the rule above.
template <class F>
void ExpectOnlySkycalErrors(F&& call) {
  try {
    call();
  } catch (const skycal::Error& e) {
    // The documented rejection.
    if (Verbose()) std::fprintf(stderr, "skycal fuzz: rejected: %s\n", e.what());
  } catch (const std::bad_alloc&) {
    throw;  // uncaught: libFuzzer reports a crash with the allocation's stack
  } catch (const std::exception& e) {
    if (Verbose()) std::fprintf(stderr, "skycal fuzz: non-skycal exception: %s\n", e.what());
    if (Strict()) {
      std::fprintf(stderr, "skycal fuzz: non-skycal exception escaped the reader: %s\n", e.what());
      std::abort();
    }
  }
}

}  // namespace skycal::fuzz
