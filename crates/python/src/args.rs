//! Turning Python arguments into the learner's types, with a `ValueError`
//! naming the problem for anything the learner would refuse or could not
//! take (never a panic: every value here comes from the user).

use std::borrow::Cow;

use learner::{Action, BodyShape, Frame, Observation};
use numpy::{AllowTypeChange, PyArrayLikeDyn, PyUntypedArrayMethods};
use pyo3::exceptions::{PyOverflowError, PyValueError};
use pyo3::prelude::*;
use pyo3::Borrowed;

/// `ValueError(text)`.
pub fn value_error(text: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(text.to_string())
}

/// The unsigned integer types [`Unsigned`] wraps.
pub trait Bounded {
    /// The largest value.
    const MAX: u128;
}

impl Bounded for u32 {
    const MAX: u128 = u32::MAX as u128;
}

impl Bounded for u64 {
    const MAX: u128 = u64::MAX as u128;
}

impl Bounded for usize {
    const MAX: u128 = usize::MAX as u128;
}

/// An unsigned integer argument. PyO3 refuses a Python int outside the
/// type's range with `OverflowError`; a negative id, seed or dimension is a
/// bad value like any other, so this makes it a `ValueError` (PyO3 adds the
/// note naming the argument).
#[derive(Clone, Copy, Debug)]
pub struct Unsigned<T>(pub T);

impl<'a, 'py, T> FromPyObject<'a, 'py> for Unsigned<T>
where
    T: FromPyObject<'a, 'py, Error = PyErr> + Bounded,
{
    type Error = PyErr;

    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        match T::extract(obj) {
            Ok(v) => Ok(Self(v)),
            Err(e) if e.is_instance_of::<PyOverflowError>(obj.py()) => {
                let shown = obj
                    .repr()
                    .map_or_else(|_| String::from("the value"), |r| r.to_string());
                Err(value_error(format!(
                    "{shown} is out of range: expected an integer in 0..={}",
                    T::MAX
                )))
            }
            Err(e) => Err(e),
        }
    }
}

/// One body of a world-state message as Python passes it:
/// `(name, id, (x, y, z), (qx, qy, qz, qw))`, or with a fifth element, its
/// shape: a `pushlearn.Shape` (or anything with its attributes
/// `sphere_radius`, `box_size`, `cylinder`) or `None`.
#[derive(Clone, Debug)]
pub struct Body(pub Observation);

impl<'a, 'py> FromPyObject<'a, 'py> for Body {
    type Error = PyErr;

    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        let items: Vec<Bound<'py, PyAny>> = obj.extract().map_err(|_| {
            value_error("a body is a tuple (name, id, (x, y, z), (qx, qy, qz, qw)[, shape])")
        })?;
        if !(4..=5).contains(&items.len()) {
            return Err(value_error(format!(
                "a body is a tuple (name, id, (x, y, z), (qx, qy, qz, qw)[, shape]), not one of \
                 {} elements",
                items.len()
            )));
        }
        let name: String = items[0].extract()?;
        let Unsigned(id) = items[1].extract::<Unsigned<u32>>()?;
        let shape = match items.get(4) {
            Some(shape) if !shape.is_none() => Some(body_shape(&name, shape)?),
            _ => None,
        };
        Ok(Self(Observation {
            position: items[2].extract()?,
            orientation: items[3].extract()?,
            name,
            id,
            shape,
        }))
    }
}

/// The shape `shape` of body `name`, read from the SDK's `Shape` by its
/// attributes; a `ValueError` naming the body unless it is one geometry
/// with finite, positive sizes.
fn body_shape(name: &str, shape: &Bound<'_, PyAny>) -> PyResult<BodyShape> {
    let attribute = |field: &str| -> PyResult<Option<Vec<f64>>> {
        let value = shape.getattr(field).map_err(|_| {
            value_error(format!(
                "the shape of body '{name}' is not a pushlearn.Shape (it has no '{field}')"
            ))
        })?;
        if value.is_none() {
            return Ok(None);
        }
        if let Ok(number) = value.extract::<f64>() {
            return Ok(Some(vec![number]));
        }
        value.extract().map(Some)
    };
    let found = match (
        attribute("sphere_radius")?.as_deref(),
        attribute("box_size")?.as_deref(),
        attribute("cylinder")?.as_deref(),
    ) {
        (Some(&[radius]), None, None) => Some(BodyShape::Sphere { radius }),
        (None, Some(&[x, y, z]), None) => Some(BodyShape::Box { size: [x, y, z] }),
        (None, None, Some(&[radius, length])) => Some(BodyShape::Cylinder { radius, length }),
        _ => None,
    };
    found.filter(|s| s.is_valid()).ok_or_else(|| {
        value_error(format!(
            "the shape of body '{name}' is not one a world can have: exactly one of \
             sphere_radius (r), box_size ((x, y, z)) or cylinder ((radius, length)), with \
             finite, positive sizes"
        ))
    })
}

/// The bodies as a [`Frame`], in the order given (the model's parser checks
/// names, ids and finiteness and refuses with a `ParseError`).
pub fn frame(bodies: Vec<Body>) -> Frame {
    Frame {
        objects: bodies.into_iter().map(|Body(o)| o).collect(),
    }
}

/// The action `(vx, vy)`, refused unless both components are finite: a
/// non-finite action would be learned and could never be forgotten.
pub fn action(vx: f64, vy: f64) -> PyResult<Action> {
    let a = Action::new(vx, vy);
    if a.is_finite() {
        Ok(a)
    } else {
        Err(value_error(format!(
            "the action (vx, vy) = ({vx}, {vy}) is not finite"
        )))
    }
}

/// `shape` as Python prints a tuple.
pub fn shape_text(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => {
            let parts: Vec<String> = shape.iter().map(usize::to_string).collect();
            format!("({})", parts.join(", "))
        }
    }
}

/// The array's elements in row-major order, borrowed when they are stored
/// so. (`as_slice` alone is not enough: it also hands out a column-major
/// array's memory, in column-major order.)
pub fn elements<'a>(array: &'a PyArrayLikeDyn<'_, f64, AllowTypeChange>) -> Cow<'a, [f64]> {
    if array.is_c_contiguous() {
        if let Ok(s) = array.as_slice() {
            return Cow::Borrowed(s);
        }
    }
    Cow::Owned(array.as_array().iter().copied().collect())
}

/// Refuses the first non-finite element of `values`, an array of `shape`
/// called `name`, naming its index.
pub fn check_finite(name: &str, values: &[f64], shape: &[usize]) -> PyResult<()> {
    let Some(flat) = values.iter().position(|v| !v.is_finite()) else {
        return Ok(());
    };
    let mut index = Vec::with_capacity(shape.len());
    let mut rest = flat;
    for &dim in shape.iter().rev() {
        let dim = dim.max(1);
        index.push(rest % dim);
        rest /= dim;
    }
    index.reverse();
    let index: Vec<String> = index.iter().map(usize::to_string).collect();
    Err(value_error(format!(
        "{name}[{}] is not finite ({})",
        index.join(", "),
        values[flat]
    )))
}

/// A 1-D array of `len` finite numbers called `name` (`what` says which
/// dimension it must match, e.g. "input_dim").
pub fn vector<'a>(
    name: &str,
    array: &'a PyArrayLikeDyn<'_, f64, AllowTypeChange>,
    len: usize,
    what: &str,
) -> PyResult<Cow<'a, [f64]>> {
    let shape = array.shape();
    if shape.len() != 1 {
        return Err(value_error(format!(
            "{name} must be a 1-D array, not one of shape {}",
            shape_text(shape)
        )));
    }
    if shape[0] != len {
        return Err(value_error(format!(
            "{name} has {} components, but the map's {what} is {len}",
            shape[0]
        )));
    }
    let values = elements(array);
    check_finite(name, &values, shape)?;
    Ok(values)
}
