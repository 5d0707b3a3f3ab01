//! Standard constrained test problems with known optima, for the solver tests only.
//!
//! References: G06, G08, G11 from Liang et al., "Problem definitions and evaluation criteria
//! for the CEC 2006 special session on constrained real-parameter optimization" (2006);
//! Binh–Korn from T. Binh, U. Korn, "MOBES: a multiobjective evolution strategy for
//! constrained optimization problems" (1997), as listed in Deb, *Multi-Objective Optimization
//! using Evolutionary Algorithms* (2001).

use std::f64::consts::PI;
use std::sync::atomic::{AtomicUsize, Ordering};

use super::problem::{Bounds, Evaluation, Problem};

/// CEC2006 G06: min (x1−10)³ + (x2−20)³, two circle constraints; f* = −6961.81387558 at
/// (14.09500000064, 0.8429607892154). The feasible region is a thin crescent.
pub struct G06(pub Bounds);
pub const G06_F: f64 = -6_961.813_875_58;
pub const G06_X: [f64; 2] = [14.095, 0.842_960_789];

impl G06 {
    pub fn new() -> Self {
        Self(Bounds::new(vec![13.0, 0.0], vec![100.0, 100.0]).unwrap())
    }
}

impl Problem for G06 {
    fn bounds(&self) -> &Bounds {
        &self.0
    }
    fn constraint_count(&self) -> usize {
        2
    }
    fn evaluate(&self, x: &[f64]) -> Evaluation {
        let (a, b) = (x[0], x[1]);
        Evaluation {
            objectives: vec![(a - 10.0).powi(3) + (b - 20.0).powi(3)],
            constraints: vec![
                -(a - 5.0).powi(2) - (b - 5.0).powi(2) + 100.0,
                (a - 6.0).powi(2) + (b - 5.0).powi(2) - 82.81,
            ],
        }
    }
}

/// CEC2006 G08: min −sin³(2πx1) sin(2πx2) / (x1³ (x1+x2)); f* = −0.0958250414180 at
/// (1.22797135, 4.24537337). Multimodal.
pub struct G08(pub Bounds);
pub const G08_F: f64 = -0.095_825_041_418_0;

impl G08 {
    pub fn new() -> Self {
        Self(Bounds::new(vec![0.0, 0.0], vec![10.0, 10.0]).unwrap())
    }
}

impl Problem for G08 {
    fn bounds(&self) -> &Bounds {
        &self.0
    }
    fn constraint_count(&self) -> usize {
        2
    }
    fn evaluate(&self, x: &[f64]) -> Evaluation {
        let (a, b) = (x[0], x[1]);
        // x1 = 0 gives 0/0: NaN, which the solvers must treat as infinitely infeasible.
        let f = -(2.0 * PI * a).sin().powi(3) * (2.0 * PI * b).sin() / (a.powi(3) * (a + b));
        Evaluation {
            objectives: vec![f],
            constraints: vec![a * a - b + 1.0, 1.0 - a + (b - 4.0).powi(2)],
        }
    }
}

/// CEC2006 G11: min x1² + (x2−1)² s.t. h = x2 − x1² = 0, written as |h| ≤ 1e-4 (two
/// inequalities); f* = 0.7499 at (±1/√2, 1/2). The feasible set is a curve.
pub struct G11(pub Bounds);
pub const G11_F: f64 = 0.7499;

impl G11 {
    pub fn new() -> Self {
        Self(Bounds::new(vec![-1.0, -1.0], vec![1.0, 1.0]).unwrap())
    }
}

impl Problem for G11 {
    fn bounds(&self) -> &Bounds {
        &self.0
    }
    fn constraint_count(&self) -> usize {
        2
    }
    fn evaluate(&self, x: &[f64]) -> Evaluation {
        let h = x[1] - x[0] * x[0];
        Evaluation {
            objectives: vec![x[0] * x[0] + (x[1] - 1.0).powi(2)],
            constraints: vec![h - 1e-4, -h - 1e-4],
        }
    }
}

/// Smooth problem: min x² + y² s.t. x + y ≥ 1 → (½, ½), f* = ½. Bounds [−2, 2]².
pub struct HalfPlane(pub Bounds);

impl HalfPlane {
    pub fn new() -> Self {
        Self(Bounds::new(vec![-2.0, -2.0], vec![2.0, 2.0]).unwrap())
    }
}

impl Problem for HalfPlane {
    fn bounds(&self) -> &Bounds {
        &self.0
    }
    fn constraint_count(&self) -> usize {
        1
    }
    fn evaluate(&self, x: &[f64]) -> Evaluation {
        Evaluation {
            objectives: vec![x[0] * x[0] + x[1] * x[1]],
            constraints: vec![1.0 - x[0] - x[1]],
        }
    }
}

/// Rosenbrock on a disk: min (1−x)² + 100(y−x²)² s.t. x² + y² ≤ 1. The constrained optimum
/// lies on the circle at (0.786415, 0.617698), f* = 0.0456748 (a curved, narrow valley meeting
/// the boundary — the "bottle neck" situation). Bounds [−1.5, 1.5]².
pub struct RosenDisk(pub Bounds);
pub const ROSEN_DISK_F: f64 = 0.045_674_8;
pub const ROSEN_DISK_X: [f64; 2] = [0.786_415, 0.617_698];

impl RosenDisk {
    pub fn new() -> Self {
        Self(Bounds::new(vec![-1.5, -1.5], vec![1.5, 1.5]).unwrap())
    }
}

impl Problem for RosenDisk {
    fn bounds(&self) -> &Bounds {
        &self.0
    }
    fn constraint_count(&self) -> usize {
        1
    }
    fn evaluate(&self, x: &[f64]) -> Evaluation {
        Evaluation {
            objectives: vec![(1.0 - x[0]).powi(2) + 100.0 * (x[1] - x[0] * x[0]).powi(2)],
            constraints: vec![x[0] * x[0] + x[1] * x[1] - 1.0],
        }
    }
}

/// Binh–Korn: min f1 = 4x² + 4y², f2 = (x−5)² + (y−5)², s.t. (x−5)² + y² ≤ 25,
/// (x−8)² + (y+3)² ≥ 7.7, x ∈ [0,5], y ∈ [0,3]. Pareto set: x = y ∈ [0,3], then y = 3,
/// x ∈ [3,5].
pub struct BinhKorn(pub Bounds);

impl BinhKorn {
    pub fn new() -> Self {
        Self(Bounds::new(vec![0.0, 0.0], vec![5.0, 3.0]).unwrap())
    }
}

impl Problem for BinhKorn {
    fn bounds(&self) -> &Bounds {
        &self.0
    }
    fn objective_count(&self) -> usize {
        2
    }
    fn constraint_count(&self) -> usize {
        2
    }
    fn evaluate(&self, x: &[f64]) -> Evaluation {
        let (a, b) = (x[0], x[1]);
        Evaluation {
            objectives: vec![
                4.0 * a * a + 4.0 * b * b,
                (a - 5.0).powi(2) + (b - 5.0).powi(2),
            ],
            constraints: vec![
                (a - 5.0).powi(2) + b * b - 25.0,
                7.7 - (a - 8.0).powi(2) - (b + 3.0).powi(2),
            ],
        }
    }
}

/// Analytic Binh–Korn front: f2 as a function of f1 ∈ [0, 136].
pub fn binh_korn_front(f1: f64) -> f64 {
    if f1 <= 72.0 {
        let x = (f1 / 8.0).sqrt();
        2.0 * (x - 5.0).powi(2)
    } else {
        let x = ((f1 - 36.0) / 4.0).sqrt();
        (x - 5.0).powi(2) + 4.0
    }
}

/// Wraps a problem and counts calls to `evaluate` (to check budgets and the observer).
pub struct Counting<P> {
    pub inner: P,
    pub calls: AtomicUsize,
}

impl<P> Counting<P> {
    pub fn new(inner: P) -> Self {
        Self {
            inner,
            calls: AtomicUsize::new(0),
        }
    }
    pub fn calls(&self) -> usize {
        self.calls.load(Ordering::SeqCst)
    }
}

impl<P: Problem> Problem for Counting<P> {
    fn bounds(&self) -> &Bounds {
        self.inner.bounds()
    }
    fn objective_count(&self) -> usize {
        self.inner.objective_count()
    }
    fn constraint_count(&self) -> usize {
        self.inner.constraint_count()
    }
    fn evaluate(&self, x: &[f64]) -> Evaluation {
        self.calls.fetch_add(1, Ordering::SeqCst);
        self.inner.evaluate(x)
    }
}

/// Sphere in 3-D with the middle variable fixed by its bounds: min Σ (x_i − 1)² s.t.
/// x0 + x2 ≥ 3, x1 ∈ [0.25, 0.25]. Optimum (1.5, 0.25, 1.5), f* = 0.5 + 0.5625.
pub struct FixedMiddle(pub Bounds);

impl FixedMiddle {
    pub fn new() -> Self {
        Self(Bounds::new(vec![-3.0, 0.25, -3.0], vec![3.0, 0.25, 3.0]).unwrap())
    }
}

impl Problem for FixedMiddle {
    fn bounds(&self) -> &Bounds {
        &self.0
    }
    fn constraint_count(&self) -> usize {
        1
    }
    fn evaluate(&self, x: &[f64]) -> Evaluation {
        Evaluation {
            objectives: vec![x.iter().map(|v| (v - 1.0).powi(2)).sum()],
            constraints: vec![3.0 - x[0] - x[2]],
        }
    }
}

pub(crate) use crate::run::sweep::one_and_many_threads;
