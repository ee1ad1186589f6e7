//! The world's calibration sweep beside the facts the thesis states.

use std::fmt::Write as _;

use crate::reproduce::calibration::CalibrationRow;

pub(super) fn calibration(rows: &[CalibrationRow]) -> String {
    let mut out = String::from("```\n");
    let _ = writeln!(
        out,
        "{:>7}  {:>13}  {:>8}  {:>8}  {:>9}  {:>11}  {:>9}",
        "x0", "first contact", "x", "y", "yaw", "translation", "rotation"
    );
    for r in rows {
        let contact = r
            .first_contact_message
            .map_or_else(|| "-".to_owned(), |m| m.to_string());
        let _ = writeln!(
            out,
            "{:>7.3}  {:>13}  {:>8.4}  {:>8.4}  {:>9.4}  {:>11.4}  {:>9.4}",
            r.x0, contact, r.block_x, r.block_y, r.block_yaw, r.translation, r.rotation
        );
    }
    out.push_str("```\n\n");
    let contact = rows.iter().filter_map(|r| r.first_contact_message).min();
    let central = rows.iter().find(|r| r.x0 == 0.0);
    let largest = rows
        .iter()
        .max_by(|a, b| a.rotation.abs().total_cmp(&b.rotation.abs()));
    let misses: Vec<String> = rows
        .iter()
        .filter(|r| r.first_contact_message.is_none())
        .map(|r| format!("{:.3}", r.x0))
        .collect();
    let _ = writeln!(out, "| Fact | Thesis | Ours |");
    let _ = writeln!(out, "|---|---|---|");
    let _ = writeln!(
        out,
        "| messages to reach the block | ≈ 35 | contact in message {} |",
        contact.map_or_else(|| "– (never)".to_owned(), |m| m.to_string())
    );
    let _ = writeln!(
        out,
        "| central push, translation | up to 0.6 m | {} |",
        central.map_or_else(|| "–".to_owned(), |r| format!("{:.3} m", r.translation))
    );
    let _ = writeln!(
        out,
        "| largest rotation | 1.02 rad at about 0.105 m from the centre | {} |",
        largest.map_or_else(
            || "–".to_owned(),
            |r| format!("{:.3} rad at x0 = {:.3} m", r.rotation.abs(), r.x0)
        )
    );
    let _ = writeln!(
        out,
        "| test positions that miss the block | 6 of 21 | {} of {} ({}) |",
        misses.len(),
        rows.len(),
        misses.join(", ")
    );
    out
}
