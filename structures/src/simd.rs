//! Which instruction set a structure's CPU kernel runs on: `--param simd=auto|scalar|sse4|avx2|avx512`
//! (issue 30). Resolved once, when the structure is built, against what this CPU has, and recorded
//! in the structure's parameters, so `results.json` says which code was timed. The kernels
//! (`kernels::cpu::lanes`) dispatch on the resolved value; `scalar` runs the shared scalar tests
//! one lane at a time and stays the oracle every SIMD kernel is checked against bit for bit.

use crate::{BuildError, Params};

/// An instruction set a kernel can be compiled for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Isa {
    /// The shared scalar tests, one lane at a time (every target).
    Scalar,
    /// 4-wide SSE (x86-64, SSE4.1).
    Sse4,
    /// 8-wide AVX2 (x86-64).
    Avx2,
    /// AVX-512 (x86-64, F and VL).
    Avx512,
}

impl Isa {
    pub fn name(self) -> &'static str {
        match self {
            Isa::Scalar => "scalar",
            Isa::Sse4 => "sse4",
            Isa::Avx2 => "avx2",
            Isa::Avx512 => "avx512",
        }
    }

    /// Whether this CPU runs it (detected at run time).
    pub fn available(self) -> bool {
        match self {
            Isa::Scalar => true,
            #[cfg(target_arch = "x86_64")]
            Isa::Sse4 => std::arch::is_x86_feature_detected!("sse4.1"),
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => std::arch::is_x86_feature_detected!("avx2"),
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => {
                std::arch::is_x86_feature_detected!("avx512f") && std::arch::is_x86_feature_detected!("avx512vl")
            }
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }
}

/// The instruction set a structure's kernel runs, resolved against this CPU. The only ways to
/// make one ([`SimdChoice::resolve`], [`Resolved::forced`]) check that the CPU has the set (the
/// field is private), so a kernel holding one may enable that set's target features: this is the
/// soundness argument of every `#[target_feature]` call in `kernels`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Resolved(Isa);

impl Resolved {
    /// The scalar tests, which run everywhere.
    pub const SCALAR: Resolved = Resolved(Isa::Scalar);

    pub fn isa(self) -> Isa {
        self.0
    }

    pub fn name(self) -> &'static str {
        self.0.name()
    }

    /// `isa`, if it is one of `supported` and this CPU has it (so one structure can be traced by
    /// its SIMD and its scalar path).
    pub fn forced(isa: Isa, supported: &[Isa]) -> Result<Self, BuildError> {
        SimdChoice::Forced(isa).resolve(supported)
    }
}

/// The instruction sets of a kernel whose tests run four lanes of SSE, or the scalar tests.
pub const FOUR_LANES: [Isa; 2] = [Isa::Scalar, Isa::Sse4];

/// The instruction sets of a kernel whose tests run eight lanes of AVX2, or the scalar tests.
pub const EIGHT_LANES: [Isa; 2] = [Isa::Scalar, Isa::Avx2];

/// The `simd` parameter: `auto` (the default) or an instruction set by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SimdChoice {
    Auto,
    Forced(Isa),
}

impl SimdChoice {
    pub const KEY: &'static str = "simd";

    pub fn from_params(params: &Params) -> Result<Self, BuildError> {
        params.choice(
            Self::KEY,
            SimdChoice::Auto,
            &[
                ("auto", SimdChoice::Auto),
                ("scalar", SimdChoice::Forced(Isa::Scalar)),
                ("sse4", SimdChoice::Forced(Isa::Sse4)),
                ("avx2", SimdChoice::Forced(Isa::Avx2)),
                ("avx512", SimdChoice::Forced(Isa::Avx512)),
            ],
        )
    }

    /// The instruction set a kernel with lanes of `supported` (widest last) runs: with `auto`, the
    /// widest of them this CPU has; a forced one must be both supported and present, or the
    /// parameter is refused saying which are.
    pub fn resolve(self, supported: &[Isa]) -> Result<Resolved, BuildError> {
        let usable: Vec<Isa> = supported.iter().copied().filter(|isa| isa.available()).collect();
        match self {
            SimdChoice::Auto => Ok(Resolved(usable.last().copied().unwrap_or(Isa::Scalar))),
            SimdChoice::Forced(isa) if usable.contains(&isa) => Ok(Resolved(isa)),
            SimdChoice::Forced(isa) => Err(BuildError::BadParam {
                key: Self::KEY.into(),
                detail: format!(
                    "'{}' is not {} here; this kernel runs {}",
                    isa.name(),
                    if supported.contains(&isa) { "available on this CPU" } else { "implemented for this structure" },
                    usable.iter().map(|i| i.name()).collect::<Vec<_>>().join(", ")
                ),
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_takes_the_widest_supported_and_present() {
        let isa = SimdChoice::Auto.resolve(&FOUR_LANES).expect("resolves").isa();
        assert_eq!(isa, if Isa::Sse4.available() { Isa::Sse4 } else { Isa::Scalar });
        assert_eq!(SimdChoice::Auto.resolve(&[Isa::Scalar]).expect("resolves"), Resolved::SCALAR);
    }

    #[test]
    fn forced_sets_must_exist_and_be_supported() {
        assert_eq!(Resolved::forced(Isa::Scalar, &FOUR_LANES).expect("ok"), Resolved::SCALAR);
        let err = Resolved::forced(Isa::Avx512, &FOUR_LANES).expect_err("refused");
        assert!(err.to_string().contains("not implemented for this structure"), "{err}");
        let params = Params::parse(["simd=neon"]).expect("parses");
        let err = SimdChoice::from_params(&params).expect_err("refused");
        assert!(err.to_string().contains("is not one of auto, scalar"), "{err}");
    }
}
