# Compiler settings shared by every target: warnings, ccache, and a lean Release.
find_program(VDBCLAY_CCACHE ccache)
if(VDBCLAY_CCACHE)
  set(CMAKE_CXX_COMPILER_LAUNCHER ${VDBCLAY_CCACHE})
endif()

add_library(vdbclay_warnings INTERFACE)
target_compile_options(vdbclay_warnings INTERFACE -Wall -Wextra -Wno-unused-parameter)

if(CMAKE_BUILD_TYPE STREQUAL "Release")
  # -O2 keeps the OpenVDB-heavy translation units within the 2-core machine's budget.
  set(CMAKE_CXX_FLAGS_RELEASE "-O2 -DNDEBUG")
endif()

# No code here reads errno after a math call; without this, every std::sqrt becomes a library call.
add_compile_options(-fno-math-errno)

# Sanitizer builds (the randomized checks and the fuzzers in CI): AddressSanitizer and UBSan on every
# target; with clang, the libraries also get libFuzzer's coverage hooks so fuzz targets can link them.
option(VDBCLAY_SANITIZE "Build with AddressSanitizer and UndefinedBehaviorSanitizer" OFF)
if(VDBCLAY_SANITIZE)
  # UBSan reports stay recoverable so that tests/sanitizer/ubsan.supp can silence the ones inside
  # Debian's TBB headers; UBSAN_OPTIONS=halt_on_error=1 still stops at every other report.
  set(vdbclay_sanitizers -fsanitize=address,undefined -fno-omit-frame-pointer)
  if(CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    list(APPEND vdbclay_sanitizers -fsanitize=fuzzer-no-link)
  endif()
  add_compile_options(${vdbclay_sanitizers})
  add_link_options(-fsanitize=address,undefined)
endif()
