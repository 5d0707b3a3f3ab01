//! Oblique impact of rough bodies: Stronge's energetic restitution with Coulomb friction
//! (physics.md §2), solved exactly in the impulse domain (≤ 3 linear segments, §2.4).
//! Newton (kinematic) and Poisson (kinetic) restitution are options for comparison.
//!
//! The obstacle (arm or guide) is kinematically driven: effectively infinite mass.

/// Placeholder; filled by the impact-map work.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ImpactLaw {
    /// Stronge's energetic coefficient (default).
    #[default]
    Energetic,
    /// Newton: u_n,f = −e u_n,0.
    Newton,
    /// Poisson: p_f = (1 + e) p_c.
    Poisson,
}
