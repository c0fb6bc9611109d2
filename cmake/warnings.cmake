# SPDX-License-Identifier: Apache-2.0
# imest_warnings(target): the project's warning wall for C targets.
set(IMEST_C_WARNINGS -Wall -Wextra -Wconversion -Wsign-conversion -Wdouble-promotion
    -Wshadow -Wcast-align -Wstrict-prototypes -Wmissing-prototypes -Wundef -Wswitch-enum)
# Clang: the per-sample range tests combine comparisons with & on purpose (no
# branch, a fixed instruction count), which its bitwise-instead-of-logical
# warning would flag.
if(CMAKE_C_COMPILER_ID MATCHES "Clang")
  list(APPEND IMEST_C_WARNINGS -Wno-bitwise-instead-of-logical)
endif()
function(imest_warnings target)
  target_compile_options(${target} PRIVATE
    $<$<COMPILE_LANGUAGE:C>:${IMEST_C_WARNINGS}>
    $<$<AND:$<COMPILE_LANGUAGE:C>,$<BOOL:${IMEST_WERROR}>>:-Werror>)
endfunction()
