// Process-wide heap policy for programs that render frames (splatffd's commands).
#pragma once

namespace sffd {

// Keeps freed heap blocks up to 32 MiB in the process for reuse instead of returning them to the kernel.
// Per frame, the GL driver and the systems allocate and free buffers of a few MiB (llvmpipe's per-draw
// and per-scene storage among them). glibc's default returns such blocks to the kernel, and the next
// frame faults them in again, page by page: the editor's first frames of a drag on a 2-core machine took
// 2-3 times as long as the ones after, and the page faults were a quarter of the main thread's time.
// Larger blocks (whole clouds) are still returned. No effect outside glibc. Call once, before the first
// allocation that matters (start of main).
void keep_freed_frame_memory();

}  // namespace sffd
