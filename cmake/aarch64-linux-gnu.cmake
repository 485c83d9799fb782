# Cross-building for aarch64 (64-bit Arm Linux) with Debian 12's cross compiler (g++-aarch64-linux-gnu)
# against arm64 multiarch libraries (libhwy-dev:arm64 and the like, in /usr/lib/aarch64-linux-gnu). Test
# programs run under qemu-user. tools/check_arm64.sh uses it:
#   cmake -S . -B build/arm64 --toolchain cmake/aarch64-linux-gnu.cmake -DSFFD_CPU_KERNELS_ONLY=ON
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
# Package configs are looked up in /usr/lib/aarch64-linux-gnu/cmake (and the architecture-independent
# /usr/share/cmake for header-only ones), never in the host's /usr/lib/x86_64-linux-gnu.
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)
set(PKG_CONFIG_EXECUTABLE aarch64-linux-gnu-pkg-config)
# ctest and gtest_discover_tests run the test programs through qemu-aarch64. No -L prefix: libc6:arm64
# comes with those libraries, so a program loads the arm64 C library, libstdc++, Highway and TBB of one
# build from the multiarch folders. With -L /usr/aarch64-linux-gnu its loader is the cross toolchain's
# (another glibc build than libc6:arm64, which the multiarch libraries still bring in), and a program
# that starts TBB threads hung there.
find_program(SFFD_QEMU_AARCH64 qemu-aarch64 REQUIRED)
set(CMAKE_CROSSCOMPILING_EMULATOR ${SFFD_QEMU_AARCH64})
