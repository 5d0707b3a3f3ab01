//! Settings that hold for a parcel class: the design set of limiting parcels and one
//! setting's capacity and margins, the capacity map over (t_c, S_d) (the paper's §4.2), the pose box, the searched worst case, robust settings
//! against it, and the machine-settings optimisation problem (§4.3).

pub mod capacity;
pub mod design_set;
pub mod pose;
pub mod robust;
pub mod settings_problem;
pub mod worst_case;
