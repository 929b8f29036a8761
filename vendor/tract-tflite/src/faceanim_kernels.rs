//! faceanim patch: a kernel tract lacks on x86-64, registered with tract-linalg's routine table
//! so that tract picks it wherever it runs: the channels-last depthwise convolution
//! (`DepthwiseC`).
//!
//! MediaPipe's TFLite models keep channels last (NHWC). tract-linalg 0.23.9 writes a vectorised
//! channels-last depthwise kernel for Arm and WebAssembly only; on x86-64 tract falls back to a
//! plain loop compiled for the baseline instruction set (SSE2, no FMA), which was an eighth of
//! all the time `faceanim adapt` spends (perf). This is that loop with AVX2 and FMA: four
//! 8-wide accumulators over 32 channels at a time, then 8 at a time, then one by one. The sums
//! run in the same order as tract's loop (bias, then taps in order), so results differ from it
//! only by FMA's single rounding.

#[cfg(target_arch = "x86_64")]
mod x86 {
    use tract_core::tract_linalg::isa::{Arch, Isa, IsaReq};
    use tract_core::tract_linalg::routines::{Func, Routine, RoutineFactory};

    /// The `DepthwiseCF32` contract: for each of `len` output positions `i`, for each channel
    /// `c < channels`, `output[i·out_stride + c] = bias[c] + Σₜ kernel[tap_indices[t]·k_stride
    /// + c] · input[i·in_stride + offsets[t] + c]`.
    ///
    /// # Safety
    /// Every pointer plus every offset that contract names must be valid, and the host must
    /// have AVX2 and FMA (tract only calls this where its ISA probe found them).
    #[allow(clippy::too_many_arguments)]
    pub unsafe fn depthwise_c_f32(
        input: *const f32,
        output: *mut f32,
        kernel: *const f32,
        tap_indices: &[usize],
        offsets: &[isize],
        bias: *const f32,
        channels: usize,
        k_stride: usize,
        len: usize,
        in_stride: isize,
        out_stride: isize,
    ) {
        // SAFETY: the caller's contract, and the ISA requirement registered below.
        unsafe {
            depthwise_c_f32_avx2(
                input,
                output,
                kernel,
                tap_indices,
                offsets,
                bias,
                channels,
                k_stride,
                len,
                in_stride,
                out_stride,
            );
        }
    }

    #[target_feature(enable = "avx2,fma")]
    #[allow(clippy::too_many_arguments)]
    unsafe fn depthwise_c_f32_avx2(
        input: *const f32,
        output: *mut f32,
        kernel: *const f32,
        tap_indices: &[usize],
        offsets: &[isize],
        bias: *const f32,
        channels: usize,
        k_stride: usize,
        len: usize,
        in_stride: isize,
        out_stride: isize,
    ) {
        use std::arch::x86_64::{_mm256_fmadd_ps, _mm256_loadu_ps, _mm256_storeu_ps};
        // SAFETY: every access below is one the contract of `depthwise_c_f32` allows.
        unsafe {
            for i in 0..len as isize {
                let x = input.offset(i * in_stride);
                let y = output.offset(i * out_stride);
                let mut c = 0usize;
                while c + 32 <= channels {
                    let mut a0 = _mm256_loadu_ps(bias.add(c));
                    let mut a1 = _mm256_loadu_ps(bias.add(c + 8));
                    let mut a2 = _mm256_loadu_ps(bias.add(c + 16));
                    let mut a3 = _mm256_loadu_ps(bias.add(c + 24));
                    for (&tap, &offset) in tap_indices.iter().zip(offsets) {
                        let k = kernel.add(tap * k_stride + c);
                        let v = x.offset(offset).add(c);
                        a0 = _mm256_fmadd_ps(_mm256_loadu_ps(k), _mm256_loadu_ps(v), a0);
                        a1 = _mm256_fmadd_ps(
                            _mm256_loadu_ps(k.add(8)),
                            _mm256_loadu_ps(v.add(8)),
                            a1,
                        );
                        a2 = _mm256_fmadd_ps(
                            _mm256_loadu_ps(k.add(16)),
                            _mm256_loadu_ps(v.add(16)),
                            a2,
                        );
                        a3 = _mm256_fmadd_ps(
                            _mm256_loadu_ps(k.add(24)),
                            _mm256_loadu_ps(v.add(24)),
                            a3,
                        );
                    }
                    _mm256_storeu_ps(y.add(c), a0);
                    _mm256_storeu_ps(y.add(c + 8), a1);
                    _mm256_storeu_ps(y.add(c + 16), a2);
                    _mm256_storeu_ps(y.add(c + 24), a3);
                    c += 32;
                }
                while c + 8 <= channels {
                    let mut a = _mm256_loadu_ps(bias.add(c));
                    for (&tap, &offset) in tap_indices.iter().zip(offsets) {
                        a = _mm256_fmadd_ps(
                            _mm256_loadu_ps(kernel.add(tap * k_stride + c)),
                            _mm256_loadu_ps(x.offset(offset).add(c)),
                            a,
                        );
                    }
                    _mm256_storeu_ps(y.add(c), a);
                    c += 8;
                }
                while c < channels {
                    let mut sum = *bias.add(c);
                    for (&tap, &offset) in tap_indices.iter().zip(offsets) {
                        sum = (*kernel.add(tap * k_stride + c))
                            .mul_add(*x.offset(offset).add(c), sum);
                    }
                    *y.add(c) = sum;
                    c += 1;
                }
            }
        }
    }

    inventory::submit! {
        Routine {
            func: Func::DepthwiseC,
            arch: Some(Arch::X86_64),
            isa: IsaReq::ANY.needing(&[Isa::X86_64Avx2, Isa::X86_64Fma]),
            boost: 0,
            round_trip: false,
            factory: RoutineFactory::DepthwiseCF32 {
                name: "faceanim_x86_64_avx2_fma_depthwise_c_f32",
                run: depthwise_c_f32,
            },
        }
    }
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    /// The kernel against the contract written out in scalar code, on odd sizes (tails of 8 and
    /// of 1), several taps and strides; run only where the host has AVX2 and FMA.
    #[test]
    fn the_depthwise_kernel_computes_the_contract() {
        if !(is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")) {
            return;
        }
        assert_eq!(
            tract_core::tract_linalg::routines::depthwise_c_f32().map(|f| f as usize),
            Some(super::x86::depthwise_c_f32 as *const () as usize),
            "tract picks this kernel"
        );
        for channels in [1, 7, 8, 32, 45, 96] {
            let (len, in_stride, out_stride) = (5usize, channels as isize * 2, channels as isize);
            let taps = [0usize, 2, 3, 5];
            let offsets = [
                0isize,
                channels as isize,
                3 * channels as isize,
                4 * channels as isize,
            ];
            let k_stride = channels;
            let value = |i: usize| ((i * 37 % 101) as f32 - 50.0) / 25.0;
            let input: Vec<f32> = (0..(len * 2 + 5) * channels).map(value).collect();
            let kernel: Vec<f32> = (0..6 * channels).map(|i| value(i + 7)).collect();
            let bias: Vec<f32> = (0..channels).map(|i| value(i + 3)).collect();
            let mut output = vec![0.0f32; len * channels];
            unsafe {
                super::x86::depthwise_c_f32(
                    input.as_ptr(),
                    output.as_mut_ptr(),
                    kernel.as_ptr(),
                    &taps,
                    &offsets,
                    bias.as_ptr(),
                    channels,
                    k_stride,
                    len,
                    in_stride,
                    out_stride,
                );
            }
            for i in 0..len {
                for c in 0..channels {
                    let mut sum = bias[c];
                    for (&t, &o) in taps.iter().zip(&offsets) {
                        sum += kernel[t * k_stride + c]
                            * input[(i as isize * in_stride + o) as usize + c];
                    }
                    let got = output[i * out_stride as usize + c];
                    assert!(
                        (got - sum).abs() < 1e-5,
                        "channels {channels}, {i}, {c}: {got} vs {sum}"
                    );
                }
            }
        }
    }
}
