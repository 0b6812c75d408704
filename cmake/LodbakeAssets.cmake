# lodbake_add_assets: bake meshes into LOD packs as part of a CMake build (docs/pipeline.md).
#
#   lodbake_add_assets(TARGET <name> PRESET <preset.json | bundled name> SOURCES <mesh>...
#                      [OUTPUT_DIR <dir>] [CACHE_DIR <dir>] [THREADS <n>] [OPTIONS <extra bake flags>...])
#
# One custom command per source: `lodbake bake SOURCE -o OUTPUT_DIR/<stem>.glb --preset PRESET
# --depfile ...`, so a source is re-baked exactly when a file it read changed (the mesh, its MTL,
# textures, .bin buffers, .conf scans, or the preset) or the baker itself changed. The depfile is
# written by lodbake and read by the generator (Ninja natively, Makefiles since CMake 3.20).
# The custom target <name> (built by ALL) depends on every pack; its LODBAKE_OUTPUTS property lists
# them. OUTPUT_DIR defaults to ${CMAKE_CURRENT_BINARY_DIR}/<name>.
#
# The baker is the imported target lodbake::lodbake (find_package(lodbake)), else the target
# `lodbake` of a build that has lodbake as a subproject, else the LODBAKE_EXECUTABLE variable.
include_guard(GLOBAL)

function(lodbake_add_assets)
    cmake_parse_arguments(PARSE_ARGV 0 arg "" "TARGET;PRESET;OUTPUT_DIR;CACHE_DIR;THREADS" "SOURCES;OPTIONS")
    if(arg_UNPARSED_ARGUMENTS)
        message(FATAL_ERROR "lodbake_add_assets: unknown arguments: ${arg_UNPARSED_ARGUMENTS}")
    endif()
    foreach(required TARGET PRESET SOURCES)
        if(NOT arg_${required})
            message(FATAL_ERROR "lodbake_add_assets: ${required} is required")
        endif()
    endforeach()

    if(TARGET lodbake::lodbake)
        set(baker lodbake::lodbake)
    elseif(TARGET lodbake)
        set(baker lodbake)
    elseif(LODBAKE_EXECUTABLE)
        set(baker "${LODBAKE_EXECUTABLE}")
    else()
        message(FATAL_ERROR "lodbake_add_assets: no lodbake baker: find_package(lodbake), add the lodbake project, "
                            "or set LODBAKE_EXECUTABLE")
    endif()

    if(arg_OUTPUT_DIR)
        get_filename_component(out_dir "${arg_OUTPUT_DIR}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_BINARY_DIR}")
    else()
        set(out_dir "${CMAKE_CURRENT_BINARY_DIR}/${arg_TARGET}")
    endif()
    if(arg_PRESET MATCHES "^[A-Za-z0-9_-]+$")
        # A bundled preset's name (`lodbake bake --preset mobile`): the depfile lists the file it names.
        set(preset "${arg_PRESET}")
        set(preset_file)
    else()
        get_filename_component(preset "${arg_PRESET}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_SOURCE_DIR}")
        set(preset_file "${preset}")
    endif()
    set(extra ${arg_OPTIONS})
    if(arg_CACHE_DIR)
        get_filename_component(cache_dir "${arg_CACHE_DIR}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_BINARY_DIR}")
        list(APPEND extra --cache-dir "${cache_dir}")
    endif()
    if(arg_THREADS)
        list(APPEND extra --threads "${arg_THREADS}")
    endif()

    set(outputs)
    set(seen)
    foreach(source IN LISTS arg_SOURCES)
        get_filename_component(source_abs "${source}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_SOURCE_DIR}")
        get_filename_component(stem "${source}" NAME_WLE)
        if(stem IN_LIST seen)
            message(FATAL_ERROR "lodbake_add_assets(${arg_TARGET}): two sources are named '${stem}'; "
                                "call lodbake_add_assets once per folder or use distinct names")
        endif()
        list(APPEND seen "${stem}")
        set(pack "${out_dir}/${stem}.glb")
        file(RELATIVE_PATH shown "${CMAKE_SOURCE_DIR}" "${source_abs}")
        add_custom_command(
            OUTPUT "${pack}"
            COMMAND "${CMAKE_COMMAND}" -E make_directory "${out_dir}"
            COMMAND ${baker} bake "${source_abs}" -o "${pack}" --preset "${preset}" --depfile "${pack}.d" --quiet
                    ${extra}
            DEPENDS "${source_abs}" ${preset_file} ${baker}
            DEPFILE "${pack}.d"
            COMMENT "Baking LOD pack ${shown}"
            VERBATIM)
        list(APPEND outputs "${pack}")
    endforeach()
    add_custom_target(${arg_TARGET} ALL DEPENDS ${outputs})
    set_property(TARGET ${arg_TARGET} PROPERTY LODBAKE_OUTPUTS ${outputs})
endfunction()
