//! Optimisation: problems with bounded variables, objectives and inequality constraints
//! g(x) ≤ 0, and the solvers that search them.
