# _texelcore, a MicroPython user C module (docs/firmware.md): the brush
# painter and format 2 (plan, int engine) in C. host/texelpad/firmware/build.py includes this file
# beside ulab's.
add_library(usermod_texelcore INTERFACE)
target_sources(usermod_texelcore INTERFACE
    ${CMAKE_CURRENT_LIST_DIR}/brush_core.c
    ${CMAKE_CURRENT_LIST_DIR}/texel_core.c
    ${CMAKE_CURRENT_LIST_DIR}/refresh_core.c
    ${CMAKE_CURRENT_LIST_DIR}/modtexelcore.c
)
target_include_directories(usermod_texelcore INTERFACE ${CMAKE_CURRENT_LIST_DIR})
# -O2 for these two files' loops (the rp2 port builds with -Os)
set_source_files_properties(${CMAKE_CURRENT_LIST_DIR}/brush_core.c ${CMAKE_CURRENT_LIST_DIR}/texel_core.c PROPERTIES COMPILE_OPTIONS "-O2")
# the refresh (refresh_core.c) and its interrupt entry (texelcore_api.h, in modtexelcore.c) run
# from RAM: pico-sdk's linker script copies .time_critical.* there (refresh_core.h TC_RAMFUNC)
set_source_files_properties(${CMAKE_CURRENT_LIST_DIR}/refresh_core.c PROPERTIES COMPILE_OPTIONS "-O2;-DTC_IN_RAM")
set_source_files_properties(${CMAKE_CURRENT_LIST_DIR}/modtexelcore.c PROPERTIES COMPILE_DEFINITIONS "TC_IN_RAM")
target_link_libraries(usermod INTERFACE usermod_texelcore)
