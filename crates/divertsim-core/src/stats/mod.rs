//! Statistics for Monte Carlo studies: special functions, exact binomial intervals and the
//! distributions a parcel mix is drawn from. Numerics only: nothing here knows of parcels.
//!
//! - [`special`]: the regularized incomplete beta function and its inverse, the normal
//!   distribution function and its inverse.
//! - [`binomial`]: the Clopper–Pearson ("exact") interval of a binomial proportion.
//! - [`distribution`]: one-dimensional distributions sampled by inversion from a uniform.
//! - [`histogram`]: a study's bins per input and its load spectra.
//! - [`loads`]: the arm's loads over a study's strokes (spectra, the largest stroke).
//! - [`splitmix`]: SplitMix64, the one small seeded generator (fixed streams from a seed).
//!
//! References: Press et al., *Numerical Recipes* 3rd ed. §6.4 (incomplete beta by its
//! continued fraction); Clopper & Pearson (1934), Biometrika 26, 404–413; Acklam's rational
//! approximation of the normal quantile, refined by one Halley step.

pub mod binomial;
pub mod distribution;
pub mod histogram;
pub mod loads;
pub mod special;
pub mod splitmix;
