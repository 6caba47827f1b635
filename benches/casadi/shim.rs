//! C entry points to the generated `mass_cqd_g` kernels for the CasADi timing harness
//! (built by run.sh as a throwaway static library outside the workspace).
#![allow(unsafe_code)]

macro_rules! export {
    ($name:ident, $scene:ident) => {
        /// `mass_cqd_g` of the scene: `m` row-major NQ×NQ, `v` = C q̇ + g.
        #[unsafe(no_mangle)]
        pub extern "C" fn $name(q: *const f64, qd: *const f64, m: *mut f64, v: *mut f64) {
            use bf_generated::$scene as s;
            // SAFETY: the harness passes arrays of NQ, NQ, NQ·NQ and NQ doubles.
            let (q, qd, m, v) = unsafe {
                (
                    &*(q as *const [f64; s::NQ]),
                    &*(qd as *const [f64; s::NQ]),
                    &mut *(m as *mut [[f64; s::NQ]; s::NQ]),
                    &mut *(v as *mut [f64; s::NQ]),
                )
            };
            s::mass_cqd_g(q, qd, &s::PARAM_DEFAULTS, m, v);
        }
    };
}

export!(bf_paper_mass_cqd_g, paper);
export!(bf_puma560_mass_cqd_g, puma560);
export!(bf_iiwa7_mass_cqd_g, iiwa7);
