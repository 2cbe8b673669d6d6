# cmake -DRAYPC=... -DDOC=docs/state.md [-DSUBCOMMAND=state-schema] -P check_docs_table.cmake
# The table of DOC between its SUBCOMMAND markers (docs/state.md: state-schema's field table,
# docs/protocol.md: protocol-schema's key tables) must be exactly what `raypc SUBCOMMAND --markdown`
# writes from the one description.
if(NOT SUBCOMMAND)
  set(SUBCOMMAND state-schema)
endif()
execute_process(COMMAND ${RAYPC} ${SUBCOMMAND} --markdown RESULT_VARIABLE code OUTPUT_VARIABLE expected ERROR_VARIABLE err)
if(NOT code EQUAL 0)
  message(FATAL_ERROR "raypc ${SUBCOMMAND} --markdown failed (${code}): ${err}")
endif()
file(READ ${DOC} doc)
set(begin "<!-- ${SUBCOMMAND} table: begin -->\n")
set(end "<!-- ${SUBCOMMAND} table: end -->")
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
  file(WRITE ${CMAKE_CURRENT_BINARY_DIR}/${SUBCOMMAND}-table.expected.md "${expected}")
  message(FATAL_ERROR "${DOC}: the table differs from the description's (${DOC} is checked, not generated). "
    "Expected table written to ${CMAKE_CURRENT_BINARY_DIR}/${SUBCOMMAND}-table.expected.md; replace the table between "
    "the markers with `raypc ${SUBCOMMAND} --markdown`.\nexpected:\n${expected}\nfound:\n${actual}")
endif()
message(STATUS "ok: the table of ${DOC} is what `raypc ${SUBCOMMAND} --markdown` writes")
