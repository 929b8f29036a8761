//! glibc's allocator, tuned once at start-up for how faceanim allocates.
//!
//! Training an adapter (candle) allocates and frees tensors of a few hundred KiB to a few MiB at
//! every step: the masked weights, their gradients, Adam's moments. glibc serves each block over
//! 128 KiB with its own `mmap` and returns it with `munmap` when freed, so every step the kernel
//! maps, clears and unmaps the same memory again. glibc raises that threshold by itself as
//! blocks are freed, but not reliably: training the adapter's two networks on 20,000 cached
//! renders took 129 s of user and 103 s of system time untuned, and 121 s and 2.9 s with blocks
//! up to [`MMAP_THRESHOLD`] taken from the heap and [`TOP_PAD`] of freed heap kept for reuse,
//! giving the same weights to the bit (`faceanim adapt`, whole command, 2 cores). On 4,000
//! renders, untuned runs took 17.8 and 28.1 s, tuned ones 13.0 and 15.1 s. The memory is kept,
//! not lost: the heap stays at most [`TOP_PAD`] above what is in use.
//!
//! ```
//! let kept = faceanim_malloc::keep_spare_heap();
//! assert_eq!(kept, cfg!(all(target_os = "linux", target_env = "gnu")));
//! let v: Vec<u8> = vec![0; 1 << 20];
//! drop(v);
//! ```

/// Blocks smaller than this come from the heap (glibc's largest threshold on 64-bit systems).
pub const MMAP_THRESHOLD: usize = 32 << 20;
/// Bytes of freed heap glibc keeps at its top instead of returning them to the kernel.
pub const TOP_PAD: usize = 64 << 20;

/// Makes glibc serve blocks under [`MMAP_THRESHOLD`] from its heap and keep [`TOP_PAD`] of
/// freed heap for reuse; whether it did (false where the C library is not glibc). Call it
/// once, first thing in `main`.
#[must_use = "say when the allocator could not be tuned"]
pub fn keep_spare_heap() -> bool {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        let set = |parameter: libc::c_int, value: usize| {
            let value = libc::c_int::try_from(value).unwrap_or(libc::c_int::MAX);
            // SAFETY: `mallopt` only changes a tuning parameter of glibc's allocator, which
            // glibc reads under its own lock; both parameters take any non-negative int up to
            // these values.
            #[allow(unsafe_code)]
            let changed = unsafe { libc::mallopt(parameter, value) };
            changed == 1
        };
        set(libc::M_MMAP_THRESHOLD, MMAP_THRESHOLD) & set(libc::M_TOP_PAD, TOP_PAD)
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu")))]
    {
        false
    }
}
