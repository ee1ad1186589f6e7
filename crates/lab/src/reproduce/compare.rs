//! Where a regenerated file first differs from the committed one: the JSON
//! path and both values for documents, the line for pages.

use serde_json::Value;

/// The first difference between two JSON documents, depth first with the
/// keys of each object in sorted order, as `path: committed X, now Y`;
/// `None` when they are equal (numbers compare exactly).
///
/// # Errors
/// Either text is not JSON (named `committed` or `now`).
pub fn first_json_difference(committed: &str, now: &str) -> Result<Option<String>, String> {
    let committed: Value = serde_json::from_str(committed)
        .map_err(|e| format!("the committed file is not JSON: {e}"))?;
    let now: Value =
        serde_json::from_str(now).map_err(|e| format!("the regenerated file is not JSON: {e}"))?;
    Ok(difference(&committed, &now, &mut String::new()))
}

fn difference(committed: &Value, now: &Value, path: &mut String) -> Option<String> {
    let here = |path: &str| {
        if path.is_empty() {
            "the document".to_owned()
        } else {
            path.to_owned()
        }
    };
    match (committed, now) {
        (Value::Object(a), Value::Object(b)) => {
            for (key, va) in a {
                let len = path.len();
                if !path.is_empty() {
                    path.push('.');
                }
                path.push_str(key);
                let found = match b.get(key) {
                    Some(vb) => difference(va, vb, path),
                    None => Some(format!("{path}: committed {}, now absent", short(va))),
                };
                path.truncate(len);
                if found.is_some() {
                    return found;
                }
            }
            b.iter()
                .find(|(key, _)| !a.contains_key(*key))
                .map(|(key, vb)| {
                    let sep = if path.is_empty() { "" } else { "." };
                    format!("{path}{sep}{key}: committed absent, now {}", short(vb))
                })
        }
        (Value::Array(a), Value::Array(b)) => {
            for (i, (va, vb)) in a.iter().zip(b).enumerate() {
                let len = path.len();
                path.push_str(&format!("[{i}]"));
                let found = difference(va, vb, path);
                path.truncate(len);
                if found.is_some() {
                    return found;
                }
            }
            (a.len() != b.len()).then(|| {
                format!(
                    "{}: committed {} entries, now {}",
                    here(path),
                    a.len(),
                    b.len()
                )
            })
        }
        (a, b) if a == b => None,
        (a, b) => Some(format!(
            "{}: committed {}, now {}",
            here(path),
            short(a),
            short(b)
        )),
    }
}

/// A value for a message: scalars as they are, containers by size.
fn short(value: &Value) -> String {
    match value {
        Value::Array(a) => format!("a list of {}", a.len()),
        Value::Object(o) => format!("an object of {} keys", o.len()),
        scalar => scalar.to_string(),
    }
}

/// The first differing line of two texts, as `line N: committed "…", now
/// "…"`; `None` when they are equal.
#[must_use]
pub fn first_line_difference(committed: &str, now: &str) -> Option<String> {
    let (mut a, mut b) = (committed.lines(), now.lines());
    for n in 1.. {
        match (a.next(), b.next()) {
            (None, None) => return (committed != now).then(|| "line endings differ".to_owned()),
            (x, y) if x == y => {}
            (x, y) => {
                let show = |l: Option<&str>| {
                    l.map_or_else(|| "end of file".to_owned(), |l| format!("{l:?}"))
                };
                return Some(format!("line {n}: committed {}, now {}", show(x), show(y)));
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_the_first_differing_value_with_its_path() {
        let a = r#"{"setup":1,"results":[{"n":1,"err":{"mean":0.25}},{"n":2,"err":{"mean":0.5}}]}"#;
        let b = r#"{"setup":1,"results":[{"n":1,"err":{"mean":0.25}},{"n":2,"err":{"mean":0.5000001}}]}"#;
        assert_eq!(
            first_json_difference(a, b).unwrap().as_deref(),
            Some("results[1].err.mean: committed 0.5, now 0.5000001")
        );
        assert_eq!(first_json_difference(a, a).unwrap(), None);
        // Formatting does not matter, values do.
        let pretty =
            serde_json::to_string_pretty(&serde_json::from_str::<Value>(a).unwrap()).unwrap();
        assert_eq!(first_json_difference(a, &pretty).unwrap(), None);
    }

    #[test]
    fn missing_extra_and_resized_values_are_named() {
        assert_eq!(
            first_json_difference(r#"{"a":1,"b":2}"#, r#"{"a":1}"#)
                .unwrap()
                .as_deref(),
            Some("b: committed 2, now absent")
        );
        assert_eq!(
            first_json_difference(r#"{"a":{"x":1}}"#, r#"{"a":{"x":1,"y":[1]}}"#)
                .unwrap()
                .as_deref(),
            Some("a.y: committed absent, now a list of 1")
        );
        assert_eq!(
            first_json_difference(r#"[1,2]"#, r#"[1,2,3]"#)
                .unwrap()
                .as_deref(),
            Some("the document: committed 2 entries, now 3")
        );
        assert!(first_json_difference("{", "{}")
            .unwrap_err()
            .contains("committed"));
    }

    #[test]
    fn pages_differ_by_line() {
        assert_eq!(first_line_difference("a\nb\nc\n", "a\nb\nc\n"), None);
        assert_eq!(
            first_line_difference("a\nb\n", "a\nB\n").as_deref(),
            Some(r#"line 2: committed "b", now "B""#)
        );
        assert_eq!(
            first_line_difference("a\n", "a\nb\n").as_deref(),
            Some(r#"line 2: committed end of file, now "b""#)
        );
    }
}
