/*
 * Test-only stand-in for Windows' bcryptprimitives.dll, for running the
 * win64 library under wine.
 *
 * Rust's standard library on Windows imports ProcessPrng from
 * bcryptprimitives.dll (present on every Windows 10 and later), but Debian's
 * wine 8 does not provide that DLL, so without this stand-in the FMU's DLL
 * fails to load under wine. conftest.py builds it with MinGW-w64
 * (`x86_64-w64-mingw32-gcc -shared`) into the folder of the win64 harness
 * (target/platforms/win64/), where the loader finds it. It is never part of
 * the FMU: tests/platforms/test_binaries.py checks that the FMU holds no such
 * file, and the DLL's expected import list names the real system DLL.
 *
 * ProcessPrng fills the buffer with random bytes from RtlGenRandom
 * (advapi32's SystemFunction036, which wine implements) and returns TRUE, as
 * the documented function does. The library only uses it to seed hash maps;
 * no simulation result depends on the bytes.
 */
#include <windows.h>

BOOLEAN WINAPI SystemFunction036(PVOID buffer, ULONG length);

__declspec(dllexport) BOOL WINAPI ProcessPrng(PBYTE data, SIZE_T length) {
    while (length > 0) {
        ULONG chunk = length > 0x10000000 ? 0x10000000 : (ULONG)length;
        if (!SystemFunction036(data, chunk)) return FALSE;
        data += chunk;
        length -= chunk;
    }
    return TRUE;
}
