//! The paper's §4 analyses: the start position R_s(v) for a reference displacement
//! (Fig. 4), capture by the arm (Fig. 5), the closed-form worst-case strike (Fig. 16) and
//! the capacity map over (t_c, S_d) (Fig. 9).

pub mod capacity;
pub mod capture;
pub mod overload;
pub mod trigger;
