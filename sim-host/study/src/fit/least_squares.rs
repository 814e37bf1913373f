//! Nonlinear least squares for every fit: Levenberg-Marquardt (the `levenberg-marquardt`
//! crate, a MINPACK port) on positive parameters, with standard errors from the Jacobian at
//! the optimum.
//!
//! Every parameter we fit (stiffnesses, lengths, drag coefficients, the added-mass constants)
//! is positive, so the optimiser works on `u_j = ln(x_j / x0_j)`: the search can never step
//! into a negative stiffness, and parameters of very different magnitudes (k1 ~ 1e3 N/m,
//! delta ~ 1e-2 m) are equally well scaled. The Jacobian is taken by central finite
//! differences (the models include a simulator, which has no analytic derivative).
//!
//! Uncertainty: with `m` residuals, `n` parameters and `s^2 = sum(r^2) / (m - n)`, the
//! covariance of the natural parameters is `s^2 (J^T J)^-1` with `J = d r / d x` evaluated at
//! the optimum; the standard error of `x_j` is the square root of its diagonal element.

use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{DMatrix, DVector, Dyn, Owned};

/// Relative finite-difference step in log-parameter space.
const LOG_STEP: f64 = 1e-5;

/// A fitted parameter vector and how well it fits.
#[derive(Clone, Debug, PartialEq)]
pub struct LeastSquaresFit {
    /// Best-fit parameters (natural units, same order as the initial guess).
    pub values: Vec<f64>,
    /// Standard error of each parameter, from `s^2 (J^T J)^-1` at the optimum.
    pub stderr: Vec<f64>,
    /// Residuals at the optimum (model - data), in the data's units.
    pub residuals: Vec<f64>,
    /// Root mean square of the residuals, in the data's units.
    pub residual_rms: f64,
    /// Number of residual-vector evaluations the optimiser used (Jacobian columns included).
    pub evaluations: usize,
}

/// Why a least-squares fit failed.
#[derive(Clone, Debug, PartialEq)]
pub enum LeastSquaresError {
    /// Not more residuals than parameters: the residual variance is undefined.
    TooFewPoints {
        /// Residuals available.
        points: usize,
        /// Parameters to fit.
        params: usize,
    },
    /// The model could not be evaluated (e.g. a simulation failed) at these parameters.
    Model(String),
    /// The optimiser stopped without converging.
    NotConverged(String),
    /// `J^T J` is singular at the optimum: the data do not constrain parameter `index`.
    Undetermined {
        /// Index of the first unconstrained parameter.
        index: usize,
    },
}

/// The residual function of a fit: `r(x)` for natural-unit parameters `x`, or an error text
/// if the model cannot be evaluated there.
pub trait Residuals {
    /// Model minus data, one entry per data point.
    fn residuals(&self, x: &[f64]) -> Result<Vec<f64>, String>;
}

impl<F: Fn(&[f64]) -> Result<Vec<f64>, String>> Residuals for F {
    fn residuals(&self, x: &[f64]) -> Result<Vec<f64>, String> {
        self(x)
    }
}

/// Minimise `sum r(x)^2` over positive `x`, starting from `initial` (all entries > 0).
pub fn fit_positive(
    model: &impl Residuals,
    initial: &[f64],
) -> Result<LeastSquaresFit, LeastSquaresError> {
    assert!(
        initial.iter().all(|x| x.is_finite() && *x > 0.0),
        "initial guesses are positive: {initial:?}"
    );
    let n = initial.len();
    let r0 = model.residuals(initial).map_err(LeastSquaresError::Model)?;
    if r0.len() <= n {
        return Err(LeastSquaresError::TooFewPoints {
            points: r0.len(),
            params: n,
        });
    }
    let problem = LogProblem {
        model,
        scale: initial.to_vec(),
        u: DVector::zeros(n),
        evaluations: std::cell::Cell::new(1),
        failure: std::cell::RefCell::new(None),
    };
    let (problem, report) = LevenbergMarquardt::new()
        .with_patience(200)
        .minimize(problem);
    if let Some(msg) = problem.failure.borrow_mut().take() {
        return Err(LeastSquaresError::Model(msg));
    }
    if !report.termination.was_successful() {
        return Err(LeastSquaresError::NotConverged(format!(
            "{:?}",
            report.termination
        )));
    }
    let values = problem.natural(&problem.u);
    let residuals = model.residuals(&values).map_err(LeastSquaresError::Model)?;
    let m = residuals.len();
    let ssr: f64 = residuals.iter().map(|r| r * r).sum();
    // Jacobian in natural units: dr/dx_j = (dr/du_j) / x_j.
    let j_log = problem
        .jacobian_log(&problem.u)
        .map_err(LeastSquaresError::Model)?;
    let j = DMatrix::from_fn(m, n, |i, c| j_log[(i, c)] / values[c]);
    let stderr = standard_errors(&j, ssr / (m - n) as f64)?;
    Ok(LeastSquaresFit {
        values,
        stderr,
        residual_rms: (ssr / m as f64).sqrt(),
        residuals,
        evaluations: problem.evaluations.get(),
    })
}

/// `sqrt(diag(s2 (J^T J)^-1))`; singular or non-finite → [`LeastSquaresError::Undetermined`].
fn standard_errors(j: &DMatrix<f64>, s2: f64) -> Result<Vec<f64>, LeastSquaresError> {
    let n = j.ncols();
    let jtj = j.transpose() * j;
    // A column of zeros (a parameter the data never feel) makes J^T J singular.
    if let Some(index) = (0..n).find(|&c| jtj[(c, c)] <= 0.0 || !jtj[(c, c)].is_finite()) {
        return Err(LeastSquaresError::Undetermined { index });
    }
    // Invert the correlation form (unit diagonal) so the condition check is scale-free.
    let d = DVector::from_fn(n, |c, _| jtj[(c, c)].sqrt());
    let corr = DMatrix::from_fn(n, n, |a, b| jtj[(a, b)] / (d[a] * d[b]));
    let svd = corr.clone().svd(false, false);
    let (min_sv, max_sv) = (svd.singular_values.min(), svd.singular_values.max());
    if min_sv.is_nan() || min_sv <= 1e-12 * max_sv {
        // Report the parameter with the largest weight in the null direction.
        let eig = corr.symmetric_eigen();
        let k = eig.eigenvalues.imin();
        let index = eig.eigenvectors.column(k).iamax();
        return Err(LeastSquaresError::Undetermined { index });
    }
    let inv = corr
        .try_inverse()
        .ok_or(LeastSquaresError::Undetermined { index: 0 })?;
    Ok((0..n).map(|c| (s2 * inv[(c, c)]).sqrt() / d[c]).collect())
}

/// The problem as the optimiser sees it: log-scaled parameters `u`, `x = x0 exp(u)`.
struct LogProblem<'a, R: Residuals> {
    model: &'a R,
    scale: Vec<f64>,
    u: DVector<f64>,
    evaluations: std::cell::Cell<usize>,
    /// First model failure, reported instead of the optimiser's generic reason.
    failure: std::cell::RefCell<Option<String>>,
}

impl<R: Residuals> LogProblem<'_, R> {
    fn natural(&self, u: &DVector<f64>) -> Vec<f64> {
        self.scale
            .iter()
            .zip(u.iter())
            .map(|(s, u)| s * u.exp())
            .collect()
    }

    fn eval(&self, u: &DVector<f64>) -> Result<DVector<f64>, String> {
        self.evaluations.set(self.evaluations.get() + 1);
        let x = self.natural(u);
        let r = self.model.residuals(&x)?;
        if r.iter().any(|v| !v.is_finite()) {
            return Err(format!(
                "the model gave a non-finite value at parameters {x:?}"
            ));
        }
        Ok(DVector::from_vec(r))
    }

    fn jacobian_log(&self, u: &DVector<f64>) -> Result<DMatrix<f64>, String> {
        let n = u.len();
        let mut columns = Vec::with_capacity(n);
        for c in 0..n {
            let mut up = u.clone();
            let mut down = u.clone();
            up[c] += LOG_STEP;
            down[c] -= LOG_STEP;
            columns.push((self.eval(&up)? - self.eval(&down)?) / (2.0 * LOG_STEP));
        }
        Ok(DMatrix::from_columns(&columns))
    }

    fn record(&self, e: String) {
        self.failure.borrow_mut().get_or_insert(e);
    }
}

impl<R: Residuals> LeastSquaresProblem<f64, Dyn, Dyn> for LogProblem<'_, R> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, u: &DVector<f64>) {
        self.u.copy_from(u);
    }

    fn params(&self) -> DVector<f64> {
        self.u.clone()
    }

    fn residuals(&self) -> Option<DVector<f64>> {
        self.eval(&self.u).map_err(|e| self.record(e)).ok()
    }

    fn jacobian(&self) -> Option<DMatrix<f64>> {
        self.jacobian_log(&self.u).map_err(|e| self.record(e)).ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_exponential_decay_is_recovered_with_zero_residual() {
        let t: Vec<f64> = (0..20).map(|i| 0.1 * i as f64).collect();
        let data: Vec<f64> = t.iter().map(|t| 3.0 * (-t / 0.7_f64).exp()).collect();
        let model = |x: &[f64]| -> Result<Vec<f64>, String> {
            Ok(t.iter()
                .zip(&data)
                .map(|(t, d)| x[0] * (-t / x[1]).exp() - d)
                .collect())
        };
        let fit = fit_positive(&model, &[1.0, 0.2]).unwrap();
        assert!((fit.values[0] - 3.0).abs() < 1e-8, "{:?}", fit.values);
        assert!((fit.values[1] - 0.7).abs() < 1e-8, "{:?}", fit.values);
        assert!(fit.residual_rms < 1e-8);
    }

    #[test]
    fn straight_line_stderr_matches_the_textbook_formula() {
        // y = a x with noise-like fixed residuals: se(a) = s / sqrt(sum x^2).
        let x: Vec<f64> = (1..=10).map(f64::from).collect();
        let wiggle = [0.1, -0.2, 0.15, -0.05, 0.0, 0.1, -0.1, 0.2, -0.15, 0.05];
        let y: Vec<f64> = x.iter().zip(wiggle).map(|(x, w)| 2.0 * x + w).collect();
        let model = |p: &[f64]| -> Result<Vec<f64>, String> {
            Ok(x.iter().zip(&y).map(|(x, y)| p[0] * x - y).collect())
        };
        let fit = fit_positive(&model, &[1.0]).unwrap();
        let sxx: f64 = x.iter().map(|x| x * x).sum();
        let a = x.iter().zip(&y).map(|(x, y)| x * y).sum::<f64>() / sxx;
        let ssr: f64 = x.iter().zip(&y).map(|(x, y)| (a * x - y).powi(2)).sum();
        let se = (ssr / 9.0 / sxx).sqrt();
        assert!((fit.values[0] - a).abs() < 1e-9);
        assert!(
            (fit.stderr[0] - se).abs() < 1e-6 * se,
            "{} vs {se}",
            fit.stderr[0]
        );
    }

    #[test]
    fn a_parameter_the_data_never_feel_is_reported_undetermined() {
        let x: Vec<f64> = (1..=10).map(f64::from).collect();
        let model = |p: &[f64]| -> Result<Vec<f64>, String> {
            Ok(x.iter().map(|x| p[0] * x - 2.0 * x).collect())
        };
        let err = fit_positive(&model, &[1.0, 5.0]).unwrap_err();
        assert_eq!(err, LeastSquaresError::Undetermined { index: 1 });
    }

    #[test]
    fn too_few_points_are_refused() {
        let model = |p: &[f64]| -> Result<Vec<f64>, String> { Ok(vec![p[0] - 1.0, p[1] - 2.0]) };
        let err = fit_positive(&model, &[1.0, 1.0]).unwrap_err();
        assert_eq!(
            err,
            LeastSquaresError::TooFewPoints {
                points: 2,
                params: 2
            }
        );
    }
}
