# cmake -DRAYPC=... -DDOC=docs/state.md -P check_docs_table.cmake
# The field table of docs/state.md (between its state-schema markers) must be exactly what
# `raypc state-schema --markdown` writes from the document's description.
execute_process(COMMAND ${RAYPC} state-schema --markdown RESULT_VARIABLE code OUTPUT_VARIABLE expected ERROR_VARIABLE err)
if(NOT code EQUAL 0)
  message(FATAL_ERROR "raypc state-schema --markdown failed (${code}): ${err}")
endif()
file(READ ${DOC} doc)
set(begin "<!-- state-schema table: begin -->\n")
set(end "<!-- state-schema table: end -->")
string(FIND "${doc}" "${begin}" b)
string(FIND "${doc}" "${end}" e)
if(b EQUAL -1 OR e EQUAL -1)
  message(FATAL_ERROR "${DOC}: no '${begin}' ... '${end}' markers around the field table")
endif()
string(LENGTH "${begin}" n)
math(EXPR b "${b} + ${n}")
math(EXPR len "${e} - ${b}")
string(SUBSTRING "${doc}" ${b} ${len} actual)
if(NOT actual STREQUAL expected)
  file(WRITE ${CMAKE_CURRENT_BINARY_DIR}/state-table.expected.md "${expected}")
  message(FATAL_ERROR "${DOC}: the field table differs from the schema's (docs/state.md is checked, not generated). "
    "Expected table written to ${CMAKE_CURRENT_BINARY_DIR}/state-table.expected.md; replace the table between "
    "the markers with `raypc state-schema --markdown`.\nexpected:\n${expected}\nfound:\n${actual}")
endif()
message(STATUS "ok: the field table of ${DOC} is the schema's")
