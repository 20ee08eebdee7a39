# GLINT_SANITIZE: build the C tests, plugins, example hosts and benchmarks with gcc's or
# clang's sanitizers, e.g.
#   cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DGLINT_SANITIZE=address,undefined
# (scripts/sanitize.sh). The Cargo-built library is not instrumented, but ASan's
# allocator and LeakSanitizer (part of ASan) see every allocation it makes through
# malloc, so its heap misuse and leaks are reported too. Any report fails the test:
# UBSan does not recover, ASan and LSan exit non-zero.
set(GLINT_SANITIZE "" CACHE STRING
    "Sanitizers for the C tests and hosts (-fsanitize= list, e.g. address,undefined); empty: none")

if(GLINT_SANITIZE)
  if(NOT GLINT_SANITIZE MATCHES "^[a-z,]+$")
    message(FATAL_ERROR "GLINT_SANITIZE=${GLINT_SANITIZE}: expected a -fsanitize= list such as address,undefined")
  endif()
  set(GLINT_SANITIZE_FLAGS -fsanitize=${GLINT_SANITIZE} -fno-sanitize-recover=all
      -fno-omit-frame-pointer)
  add_compile_options("$<$<COMPILE_LANGUAGE:C,CXX>:${GLINT_SANITIZE_FLAGS}>")
  add_link_options(${GLINT_SANITIZE_FLAGS})
  # An uninstrumented program that loads an instrumented plugin (glint-verify, a Rust
  # binary) needs the ASan runtime loaded first: the tests that run one preload it.
  set(GLINT_SANITIZE_PRELOAD "")
  if(GLINT_SANITIZE MATCHES "address")
    execute_process(COMMAND ${CMAKE_C_COMPILER} -print-file-name=libasan.so
                    OUTPUT_VARIABLE GLINT_SANITIZE_PRELOAD OUTPUT_STRIP_TRAILING_WHITESPACE)
  endif()
  message(STATUS "glint: C tests and hosts built with -fsanitize=${GLINT_SANITIZE}")
endif()
