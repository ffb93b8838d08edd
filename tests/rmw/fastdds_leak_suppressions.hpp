// Included once by each executable of the DDS Security tests: Fast DDS 2.9.1 leaks the certificate
// of every remote participant whose authentication it refuses (PKIDH::begin_handshake_reply reads
// it and never frees it), which LeakSanitizer would report at exit. These hooks are read only by a
// sanitizer build; the leak is suppressed by that function alone, so a leak of our own still shows.
#pragma once

// The frames of the leaked certificate run through libcrypto, which has no frame pointers: only
// the slow unwinder reaches Fast DDS's frame.
extern "C" const char* __asan_default_options() {
  return "fast_unwind_on_malloc=0";
}

extern "C" const char* __lsan_default_suppressions() {
  return "leak:eprosima::fastrtps::rtps::security::PKIDH::begin_handshake_reply\n";
}
