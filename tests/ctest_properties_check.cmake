# Fails when a registered test has no LABELS or no TIMEOUT of its own.
#
#   cmake -DCTEST=ctest -DBUILD_DIR=build -P tests/ctest_properties_check.cmake
#
# Labels select the suites (CI's sanitizer half picks tests by label) and a timeout of its own
# keeps one hung test from eating the whole run; gtest_discover_tests drops both when given a
# list in PROPERTIES (DEVELOPERS.md), so this reads what ctest itself ended up with.
execute_process(COMMAND ${CTEST} --test-dir ${BUILD_DIR} --show-only=json-v1
                OUTPUT_VARIABLE json RESULT_VARIABLE rc ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "ctest --show-only failed (${rc}): ${err}")
endif()
string(JSON count LENGTH "${json}" tests)
if(count LESS 50)
  message(FATAL_ERROR "only ${count} tests listed: discovery failed?")
endif()
set(bad "")
math(EXPR last "${count} - 1")
foreach(i RANGE ${last})
  string(JSON name GET "${json}" tests ${i} name)
  # A test program this build tree did not build (the sanitizer builds make only some) shows
  # as CMake's placeholder NAME_NOT_BUILT: there is nothing to check.
  if(name MATCHES "_NOT_BUILT$")
    continue()
  endif()
  string(JSON props ERROR_VARIABLE no_props GET "${json}" tests ${i} properties)
  set(has_labels FALSE)
  set(has_timeout FALSE)
  if(NOT no_props)
    string(JSON nprops LENGTH "${props}")
    if(nprops GREATER 0)
      math(EXPR plast "${nprops} - 1")
      foreach(j RANGE ${plast})
        string(JSON pname GET "${props}" ${j} name)
        if(pname STREQUAL "LABELS")
          set(has_labels TRUE)
        elseif(pname STREQUAL "TIMEOUT")
          set(has_timeout TRUE)
        endif()
      endforeach()
    endif()
  endif()
  if(NOT has_labels OR NOT has_timeout)
    list(APPEND bad "${name} (labels: ${has_labels}, timeout: ${has_timeout})")
  endif()
endforeach()
if(bad)
  list(JOIN bad "\n  " lines)
  message(FATAL_ERROR "tests without a label or a timeout of their own:\n  ${lines}")
endif()
message(STATUS "every built test of the ${count} listed has labels and a timeout")
