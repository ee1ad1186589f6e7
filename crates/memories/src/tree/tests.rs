//! Tests of the trees' shared arena helpers.

use super::majority;

#[test]
fn majority_prefers_the_lower_label_on_ties() {
    assert_eq!(majority(&[]), None);
    assert_eq!(majority(&[0.0, 0.0]), None);
    assert_eq!(majority(&[1.0, 3.0, 3.0]), Some(1));
    assert_eq!(majority(&[2.0, 0.0, 1.0]), Some(0));
}
