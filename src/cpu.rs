//! Which instruction sets the kernels may use: what the CPU has, capped by the environment
//! variable `MCRT_MAX_ISA`. With `MCRT_MAX_ISA=avx2` no AVX-512 code runs (the lanes take
//! two AVX2 registers, the packets' box tests eight rays, brute force its AVX kernel), as on
//! a CPU without AVX-512, so that a benchmark on an AVX-512 host can time the code an AVX2
//! host runs; Embree's `max_isa` setting and Dr.Jit's `jit_llvm_set_target` do the same for
//! Mitsuba (`bench/side_by_side.py --max-isa avx2`). Every kernel computes the same bits,
//! so the image does not depend on it.

/// The values `MCRT_MAX_ISA` may take, widest first (unset: the CPU's best).
pub const MAX_ISA_VALUES: [&str; 2] = ["avx512", "avx2"];

/// `MCRT_MAX_ISA`'s value, checked: `Ok(None)` where it is unset, an error naming the
/// accepted values where it is anything else.
pub fn max_isa() -> Result<Option<&'static str>, String> {
    match std::env::var("MCRT_MAX_ISA") {
        Err(std::env::VarError::NotPresent) => Ok(None),
        Ok(v) if v.is_empty() => Ok(None),
        Ok(v) => MAX_ISA_VALUES
            .iter()
            .find(|&&k| k == v)
            .map(|&k| Some(k))
            .ok_or_else(|| format!("MCRT_MAX_ISA is {v:?}; expected one of {MAX_ISA_VALUES:?}")),
        Err(e) => Err(format!("MCRT_MAX_ISA: {e}")),
    }
}

/// Whether the AVX-512 kernels may run: the CPU has AVX-512F and `MCRT_MAX_ISA` does not
/// cap it (an invalid value caps nothing; the CLI refuses it first). Read once.
#[cfg(target_arch = "x86_64")]
pub fn avx512() -> bool {
    static ALLOWED: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *ALLOWED.get_or_init(|| {
        std::arch::is_x86_feature_detected!("avx512f")
            && !matches!(max_isa(), Ok(Some(cap)) if cap != "avx512")
    })
}
