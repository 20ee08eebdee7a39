# cmake -DGUIDE=<docs/writing-a-plugin.md> -DSOURCE=<plugins/minimal.c> -P check_guide.cmake
# Fails unless the guide's first C code block is exactly SOURCE, so that the example it
# shows is the one the build compiles and the tests load.
file(READ "${GUIDE}" guide)
file(READ "${SOURCE}" source)
string(FIND "${guide}" "\n```c\n" begin)
if(begin EQUAL -1)
  message(FATAL_ERROR "${GUIDE}: no ```c code block")
endif()
math(EXPR begin "${begin} + 6")
string(SUBSTRING "${guide}" ${begin} -1 rest)
string(FIND "${rest}" "\n```\n" end)
if(end EQUAL -1)
  message(FATAL_ERROR "${GUIDE}: the first ```c code block does not end")
endif()
math(EXPR end "${end} + 1")
string(SUBSTRING "${rest}" 0 ${end} block)
if(NOT block STREQUAL source)
  message(FATAL_ERROR "${GUIDE}: its first C code block differs from ${SOURCE}; "
                      "paste the file into the guide again")
endif()
