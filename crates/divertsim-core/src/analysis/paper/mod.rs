//! The paper's one-setting analyses: the start position R_s(v) for a reference displacement
//! (Fig. 4), capture by the arm (Fig. 5) and the closed-form worst-case strike (Fig. 16).
//! The capacity map over (t_c, S_d) (Fig. 9) is built on the design set, in
//! [`crate::analysis::design::capacity`].

pub mod capture;
pub mod overload;
pub mod trigger;
