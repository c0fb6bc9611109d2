# imest_warnings(target): the project's warning wall for C targets.
set(IMEST_C_WARNINGS -Wall -Wextra -Wconversion -Wsign-conversion -Wdouble-promotion
    -Wshadow -Wcast-align -Wstrict-prototypes -Wmissing-prototypes -Wundef -Wswitch-enum)
function(imest_warnings target)
  target_compile_options(${target} PRIVATE
    $<$<COMPILE_LANGUAGE:C>:${IMEST_C_WARNINGS}>
    $<$<AND:$<COMPILE_LANGUAGE:C>,$<BOOL:${IMEST_WERROR}>>:-Werror>)
endfunction()
