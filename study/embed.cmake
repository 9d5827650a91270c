# embed.cmake — writes file SRC as a NUL-terminated C char array VAR into OUT (cmake -P script).
file(READ "${SRC}" hex HEX)
string(REGEX REPLACE "([0-9a-f][0-9a-f])" "0x\\1," body "${hex}")
file(WRITE "${OUT}" "/* generated from ${SRC} */\nstatic const char ${VAR}[] = {${body}0x00};\n")
