# Every test writes its scratch files into its own folder (tests/test_tmp.h), never straight into
# KASKAD_TEST_TMP, where two tests that CTest runs side by side would race on one file name.
# The shader binary cache is the one folder the tests share on purpose: it is written atomically,
# as it is by two players started together.
# Usage: cmake -DSOURCE_DIR=<repo> -P check_test_tmp.cmake
file(GLOB_RECURSE sources "${SOURCE_DIR}/tests/*.cpp" "${SOURCE_DIR}/tests/*.h")
set(found "")
foreach(source IN LISTS sources)
  if(source MATCHES "/tests/test_tmp\\.h$")
    continue()
  endif()
  file(STRINGS "${source}" lines REGEX "path\\(KASKAD_TEST_TMP\\)")
  foreach(line IN LISTS lines)
    if(NOT line MATCHES "\"shader_cache\"")
      file(RELATIVE_PATH rel "${SOURCE_DIR}" "${source}")
      string(STRIP "${line}" line)
      string(APPEND found "  ${rel}: ${line}\n")
    endif()
  endforeach()
endforeach()
if(found)
  message(FATAL_ERROR "tests write straight into KASKAD_TEST_TMP; use testing_util::test_tmp() "
                      "(tests/test_tmp.h):\n${found}")
endif()
message(STATUS "every test writes into its own scratch folder")
