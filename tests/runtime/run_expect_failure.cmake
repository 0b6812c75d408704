# A control test: runs PROGRAM with ARGS (one string, split like a shell command line) and passes
# only when it exits with EXPECT_EXIT and its stderr contains EXPECT_STDERR. A run broken on purpose
# must fail for the reason it was broken for: a crash, a timeout, another exit code or another
# message fails the control (CTest's WILL_FAIL would accept any of them).
#   cmake -DPROGRAM=EXE -DARGS="ARG ..." -DEXPECT_EXIT=N -DEXPECT_STDERR=TEXT -P run_expect_failure.cmake
foreach(var PROGRAM EXPECT_EXIT EXPECT_STDERR)
    if(NOT DEFINED ${var})
        message(FATAL_ERROR "run_expect_failure.cmake: ${var} not set")
    endif()
endforeach()
separate_arguments(args UNIX_COMMAND "${ARGS}")
execute_process(COMMAND "${PROGRAM}" ${args} RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
string(REGEX MATCHALL "summary:[^\n]*" summary "${out}")
string(REPLACE ";" "\n" summary "${summary}")
message("${summary}\n${err}")
if(NOT "${code}" STREQUAL "${EXPECT_EXIT}")
    message(FATAL_ERROR "expected exit code ${EXPECT_EXIT}, got ${code}")
endif()
string(FIND "${err}" "${EXPECT_STDERR}" at)
if(at EQUAL -1)
    message(FATAL_ERROR "stderr does not contain \"${EXPECT_STDERR}\"")
endif()
