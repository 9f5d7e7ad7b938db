# Run after lcm-gen on its C++ headers (cmake -DDIR=... -P lcm_gen_fix.cmake).
# lcm-gen's string decode checks only that a string's length field is not
# beyond the message, then assigns `length - 1` characters: a length of 0 or
# below asks std::string for ~2^64 (length_error), and INT32_MIN overflows
# (undefined) into INT32_MAX, a 2 GB read past the message. Found by
# tests/fuzz/lcm_fuzz; every string length below 1 is refused here instead.
file(GLOB _headers ${DIR}/*.hpp)
foreach(_h IN LISTS _headers)
  file(READ ${_h} _text)
  string(REGEX REPLACE "if\\(__([A-Za-z0-9_]+) > maxlen - pos\\) return -1;"
         "if(__\\1 < 1 || __\\1 > maxlen - pos) return -1;" _text "${_text}")
  if(_text MATCHES "\\.assign\\(" AND NOT _text MATCHES "< 1 \\|\\| __")
    message(FATAL_ERROR "lcm_gen_fix.cmake: ${_h} decodes a string but no length check was patched "
                        "(lcm-gen's output changed?)")
  endif()
  file(WRITE ${_h} "${_text}")
endforeach()
