# EPIPOLE_SANITIZE is a comma-separated list handed to -fsanitize (e.g. "address,undefined").
set(EPIPOLE_SANITIZE "" CACHE STRING "Sanitizers to build with, e.g. address,undefined")
if(EPIPOLE_SANITIZE)
  add_compile_options(-fsanitize=${EPIPOLE_SANITIZE} -fno-omit-frame-pointer
                      -fno-sanitize-recover=all)
  add_link_options(-fsanitize=${EPIPOLE_SANITIZE})
endif()
