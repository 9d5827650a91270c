# lsan_env.sh — sourced by the shell tests: LeakSanitizer checks every taslab process they start. ctest passes
# TASLAB_LSAN_PIN (tests/CMakeLists.txt), the preload library that keeps the Vulkan driver and layer loaded in taslab
# processes so that lsan.supp applies (tests/lsan_pin.c; it does nothing in other programs, so exporting it is safe);
# LSAN_OPTIONS (the suppressions, intercept_tls_get_addr=0: tests/CMakeLists.txt) comes from ctest too. A leak makes
# taslab exit non-zero and the script fail.
# Run by hand without TASLAB_LSAN_PIN, leak checking is off (the unpinned driver's state would be reported).
if [ -n "${TASLAB_LSAN_PIN:-}" ]; then
  export LD_PRELOAD="$TASLAB_LSAN_PIN" ASAN_OPTIONS=detect_leaks=1:verify_asan_link_order=0:quarantine_size_mb=8
else
  export ASAN_OPTIONS=detect_leaks=0:quarantine_size_mb=8
fi
