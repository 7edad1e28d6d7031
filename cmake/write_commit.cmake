# Writes OUT, a header that names the commit of the source tree SRC: its hash in 12 hex digits, with
# "-dirty" when the tree has uncommitted changes (`git describe` with every tag excluded, so that a
# tag never stands in for the hash); "unknown" outside a git checkout or without git. The custom
# target talus_commit runs this at every build; the file is rewritten only when its text changes, so
# a build of the same commit compiles nothing again.
execute_process(COMMAND git -C "${SRC}" describe --always --dirty --abbrev=12 --exclude=*
                OUTPUT_VARIABLE commit OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET RESULT_VARIABLE rc)
if(NOT rc EQUAL 0 OR commit STREQUAL "")
  set(commit "unknown")
endif()
set(text "#pragma once\n// Written at build time by cmake/write_commit.cmake: the commit this build was made from.\nnamespace talus {\ninline constexpr const char* kCommit = \"${commit}\";\n}\n")
set(old "")
if(EXISTS "${OUT}")
  file(READ "${OUT}" old)
endif()
if(NOT old STREQUAL text)
  file(WRITE "${OUT}" "${text}")
endif()
