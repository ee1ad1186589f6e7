//! `Aitm`: the Adapted Instantaneous Topological Map (`learner::aitm`,
//! `docs/spec/aitm.md`) as a stand-alone regressor and classifier.

use learner::aitm::{Aitm, AitmParams, QueryMode, EPS_MAX, SIGMA};
use numpy::{AllowTypeChange, PyArray1, PyArrayLikeDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::PyMemoryError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::args::{self, value_error, Unsigned};

/// The largest `max(input_dim, 1) · max(output_dim, 1)` a map may have: a
/// node's linear map has that many numbers, and a query of an empty map
/// allocates `output_dim` of them, so absurd dimensions must be refused
/// before they become an allocation failure, which aborts the process.
const MAX_DIM_PRODUCT: usize = 1 << 24;

/// The query modes by name (`docs/spec/aitm.md` §3), as they are compared:
/// lower case.
const MODES: [(&str, QueryMode); 3] = [
    ("winner", QueryMode::Winner),
    ("besttwo", QueryMode::BestTwo),
    ("neighbour", QueryMode::Neighbour),
];

fn mode_name(mode: QueryMode) -> &'static str {
    MODES
        .iter()
        .find(|(_, m)| *m == mode)
        .map_or("?", |(name, _)| name)
}

fn parse_mode(name: &str) -> PyResult<QueryMode> {
    let lower = name.to_ascii_lowercase();
    MODES
        .iter()
        .find(|(n, _)| *n == lower)
        .map(|(_, m)| *m)
        .ok_or_else(|| {
            let names: Vec<&str> = MODES.iter().map(|(n, _)| *n).collect();
            value_error(format!(
                "unknown AITM mode '{name}'; one of: {}",
                names.join(", ")
            ))
        })
}

/// The Adapted Instantaneous Topological Map (docs/spec/aitm.md): a growing
/// graph of nodes in input space, each with an output vector and a local
/// linear map; nodes are inserted where the map's own answer to a training
/// sample is wrong.
///
/// Aitm(input_dim, output_dim, *, mode, sigma=0.05, eps_max=0.001,
///      eta_in=0.0, eta_out=0.0, eta_a=0.0, classifier=False)
///
/// mode is the query mode, used for queries and for the map's own estimate
/// during update: "winner", "besttwo" or "neighbour" (case does not matter).
/// sigma is the width of the Gaussian interpolation weights, eps_max the
/// distance below which no node is inserted, eta_in / eta_out / eta_a the
/// winner's learning rates (0 in every evaluated instance), classifier whether
/// outputs are integer class labels. The defaults are the evaluated
/// instances' (learner::aitm::AitmParams::regressor); the gate model's
/// predictors use "besttwo", its classifiers and the interaction model's
/// maps "winner". Invalid values raise ValueError with the Rust check's text.
///
/// Arrays may be anything numpy.asarray turns into float64 numbers.
///
/// Thread safety: usable from any thread; every method holds the GIL
/// throughout.
#[pyclass(module = "pushlearn._native", name = "Aitm")]
#[derive(Clone)]
pub struct PyAitm {
    map: Aitm,
}

#[pymethods]
impl PyAitm {
    #[new]
    #[pyo3(
        signature = (input_dim, output_dim, *, mode, sigma = SIGMA, eps_max = EPS_MAX, eta_in = 0.0, eta_out = 0.0, eta_a = 0.0, classifier = false),
        text_signature = "(input_dim, output_dim, *, mode, sigma=0.05, eps_max=0.001, eta_in=0.0, eta_out=0.0, eta_a=0.0, classifier=False)"
    )]
    #[allow(clippy::too_many_arguments)] // the Python keyword arguments, one per AitmParams field
    fn new(
        input_dim: Unsigned<usize>,
        output_dim: Unsigned<usize>,
        mode: &str,
        sigma: f64,
        eps_max: f64,
        eta_in: f64,
        eta_out: f64,
        eta_a: f64,
        classifier: bool,
    ) -> PyResult<Self> {
        let (input_dim, output_dim) = (input_dim.0, output_dim.0);
        let fits = input_dim
            .max(1)
            .checked_mul(output_dim.max(1))
            .is_some_and(|p| p <= MAX_DIM_PRODUCT);
        if !fits {
            return Err(value_error(format!(
                "input_dim {input_dim} × output_dim {output_dim} is too large \
                 (at most {MAX_DIM_PRODUCT} numbers per node)"
            )));
        }
        let config = AitmParams {
            sigma,
            eps_max,
            eta_in,
            eta_out,
            eta_a,
            mode: parse_mode(mode)?,
            classifier,
        }
        .check()
        .map_err(value_error)?;
        Ok(Self {
            map: Aitm::new(config, input_dim, output_dim),
        })
    }

    /// One training step update(x, y) (docs/spec/aitm.md §4): x is a 1-D
    /// array of input_dim finite numbers, y one of output_dim.
    ///
    /// Raises ValueError if either has the wrong shape or a non-finite
    /// element (naming which).
    fn update(
        &mut self,
        x: PyArrayLikeDyn<'_, f64, AllowTypeChange>,
        y: PyArrayLikeDyn<'_, f64, AllowTypeChange>,
    ) -> PyResult<()> {
        let x = args::vector("x", &x, self.map.input_dim(), "input_dim")?;
        let y = args::vector("y", &y, self.map.output_dim(), "output_dim")?;
        self.map.update(&x, &y);
        Ok(())
    }

    /// Train a one-output map with the integer class label `label`
    /// (update(x, [label])); x as for update.
    ///
    /// Raises ValueError unless output_dim is 1, or for a bad x.
    fn update_label(
        &mut self,
        x: PyArrayLikeDyn<'_, f64, AllowTypeChange>,
        label: i64,
    ) -> PyResult<()> {
        if self.map.output_dim() != 1 {
            return Err(value_error(format!(
                "update_label needs a one-output map (output_dim is {})",
                self.map.output_dim()
            )));
        }
        let x = args::vector("x", &x, self.map.input_dim(), "input_dim")?;
        self.map.update_label(&x, label);
        Ok(())
    }

    /// The map's answer f(x, mode) (docs/spec/aitm.md §3); zeros for a map
    /// that was never trained.
    ///
    /// x is a 1-D array of input_dim finite numbers (the result is a 1-D
    /// float64 array of output_dim numbers) or a 2-D array of shape
    /// (n, input_dim), one input per row (the result has shape
    /// (n, output_dim)). Raises ValueError for another shape or a
    /// non-finite element.
    fn predict<'py>(
        &self,
        py: Python<'py>,
        x: PyArrayLikeDyn<'py, f64, AllowTypeChange>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (n, m) = (self.map.input_dim(), self.map.output_dim());
        let shape = x.shape().to_vec();
        match shape[..] {
            [_] => {
                let x = args::vector("x", &x, n, "input_dim")?;
                Ok(PyArray1::from_vec(py, self.map.query(&x)).into_any())
            }
            [rows, cols] => {
                if cols != n {
                    return Err(value_error(format!(
                        "x has rows of {cols} components, but the map's input_dim is {n}"
                    )));
                }
                let values = args::elements(&x);
                args::check_finite("x", &values, &shape)?;
                let mut out = Vec::new();
                rows.checked_mul(m)
                    .and_then(|len| out.try_reserve_exact(len).ok())
                    .ok_or_else(|| {
                        PyMemoryError::new_err(format!("no memory for {rows} × {m} predictions"))
                    })?;
                if n == 0 {
                    // Rows of no components: every row is the empty input.
                    for _ in 0..rows {
                        out.extend(self.map.query(&[]));
                    }
                } else {
                    for row in values.chunks_exact(n) {
                        out.extend(self.map.query(row));
                    }
                }
                Ok(PyArray1::from_vec(py, out).reshape([rows, m])?.into_any())
            }
            _ => Err(value_error(format!(
                "x must be a 1-D or 2-D array, not one of shape {}",
                args::shape_text(&shape)
            ))),
        }
    }

    /// The classifier's answer (docs/spec/aitm.md §6): the winner's label
    /// for the 1-D input x, or None if the map was never trained or has no
    /// output. x as for update.
    fn classify(&self, x: PyArrayLikeDyn<'_, f64, AllowTypeChange>) -> PyResult<Option<i64>> {
        let x = args::vector("x", &x, self.map.input_dim(), "input_dim")?;
        Ok(self.map.classify(&x))
    }

    /// The current number of nodes.
    #[getter]
    fn node_count(&self) -> usize {
        self.map.len()
    }

    /// The input dimension.
    #[getter]
    fn input_dim(&self) -> usize {
        self.map.input_dim()
    }

    /// The output dimension.
    #[getter]
    fn output_dim(&self) -> usize {
        self.map.output_dim()
    }

    /// The map's counters: {"update_calls": int, "inserts": int (nodes ever
    /// inserted), "nodes": int (current nodes)}.
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = self.map.stats();
        let d = PyDict::new(py);
        d.set_item("update_calls", s.update_calls)?;
        d.set_item("inserts", s.inserts)?;
        d.set_item("nodes", s.nodes)?;
        Ok(d)
    }

    /// A deep copy of the map.
    fn copy(&self) -> Self {
        self.clone()
    }

    fn __repr__(&self) -> String {
        let p = self.map.config().params();
        format!(
            "Aitm(input_dim={}, output_dim={}, mode='{}', sigma={:?}, eps_max={:?}, \
             eta_in={:?}, eta_out={:?}, eta_a={:?}, classifier={}; nodes={})",
            self.map.input_dim(),
            self.map.output_dim(),
            mode_name(p.mode),
            p.sigma,
            p.eps_max,
            p.eta_in,
            p.eta_out,
            p.eta_a,
            if p.classifier { "True" } else { "False" },
            self.map.len()
        )
    }
}
