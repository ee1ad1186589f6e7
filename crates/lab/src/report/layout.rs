//! A printed table as data: its columns and cells give both the terminal
//! layout (padded, ours beside [the thesis's]) and a CSV file (`--csv DIR`:
//! one value a field, full precision, units in the header), so that the two
//! cannot disagree.

use std::io::{self, Write};
use std::path::{Path, PathBuf};

use learner::eval::MeanStd;

use super::reference::Ms;
use drive::output::write_atomically;

/// How a column's cells are printed and split into CSV fields.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Text, one field.
    Text,
    /// A number printed with `decimals`, one field.
    Number { decimals: usize },
    /// Mean ± spread of a value over folds, then [the thesis's] if
    /// `thesis`: fields mean, std (and the thesis's mean, std).
    Error { thesis: bool },
    /// Mean (spread) of a count over folds, then [the thesis's]: fields as
    /// [`Kind::Error`].
    Count { thesis: bool },
    /// Cells printed as composed text ([`Cell::Composed`]) whose values
    /// are these CSV fields.
    Composed(Vec<String>),
}

/// A column: its heading (with the unit in brackets, as "x0 [m]"), its
/// width on the terminal, and its kind.
#[derive(Clone, Debug)]
pub struct Column {
    pub head: String,
    pub width: usize,
    /// Right-aligned on the terminal (numbers and counts of the first
    /// column), else left-aligned.
    pub right: bool,
    pub kind: Kind,
}

impl Column {
    #[must_use]
    pub fn new(head: &str, width: usize, right: bool, kind: Kind) -> Self {
        Self {
            head: head.to_owned(),
            width,
            right,
            kind,
        }
    }

    /// The CSV headings: the heading split into its fields, the unit kept
    /// on each ("block position mean [m]", "… std [m]", "… thesis mean
    /// [m]", "… thesis std [m]").
    fn csv_heads(&self) -> Vec<String> {
        let (name, unit) = match self.head.find(" [") {
            Some(at) => (&self.head[..at], &self.head[at..]),
            None => (self.head.as_str(), ""),
        };
        let fields: &[&str] = match &self.kind {
            Kind::Text | Kind::Number { .. } => return vec![self.head.clone()],
            Kind::Composed(heads) => return heads.clone(),
            Kind::Error { thesis: true } | Kind::Count { thesis: true } => {
                &["mean", "std", "thesis mean", "thesis std"]
            }
            Kind::Error { thesis: false } | Kind::Count { thesis: false } => &["mean", "std"],
        };
        fields.iter().map(|f| format!("{name} {f}{unit}")).collect()
    }
}

/// One cell: a value of its column's kind (`None`: not measured, "–").
#[derive(Clone, Debug)]
pub enum Cell {
    Text(String),
    Number(f64),
    /// Ours over `folds` folds, and the thesis's where it has the value.
    Spread {
        ours: Option<MeanStd>,
        folds: usize,
        thesis: Option<Ms>,
    },
    /// Text made of several values (e.g. ours and [the thesis's]), and
    /// those values as the CSV fields of a [`Kind::Composed`] column.
    Composed {
        text: String,
        fields: Vec<String>,
    },
}

impl Cell {
    /// Ours over `folds` folds beside the thesis's value.
    #[must_use]
    pub fn spread(ours: MeanStd, folds: usize, thesis: Option<Ms>) -> Self {
        Cell::Spread {
            ours: Some(ours),
            folds,
            thesis,
        }
    }
}

/// A spread is shown for more than one fold only: the std of one sample is
/// 0 by definition, not a measured spread.
fn spread_shown(folds: usize) -> bool {
    folds > 1
}

/// A number as a CSV field: in full (shortest round-trip form), empty when
/// not finite.
#[must_use]
pub fn field(v: f64) -> String {
    if v.is_finite() {
        v.to_string()
    } else {
        String::new()
    }
}

/// A cell's text on the terminal, unpadded.
#[must_use]
pub fn text(cell: &Cell, kind: &Kind) -> String {
    match (cell, kind) {
        (Cell::Text(t) | Cell::Composed { text: t, .. }, _) => t.clone(),
        (Cell::Number(v), Kind::Number { decimals }) => format!("{v:.decimals$}"),
        (Cell::Number(v), _) => v.to_string(),
        (
            Cell::Spread {
                ours,
                folds,
                thesis,
            },
            kind,
        ) => {
            let count = matches!(kind, Kind::Count { .. });
            let ours = ours.map_or_else(
                || "–".to_owned(),
                |m| match (count, spread_shown(*folds)) {
                    (false, true) => format!("{:.4} ± {:.4}", m.mean, m.std),
                    (false, false) => format!("{:.4}", m.mean),
                    (true, true) => format!("{:.2} ({:.2})", m.mean, m.std),
                    (true, false) => format!("{:.2}", m.mean),
                },
            );
            let with_thesis = matches!(
                kind,
                Kind::Error { thesis: true } | Kind::Count { thesis: true }
            );
            if !with_thesis {
                return ours;
            }
            let reference = thesis.map_or_else(String::new, |Ms(m, s)| {
                if count {
                    format!("[{m} ({s})]")
                } else {
                    format!("[{m:.4} ± {s:.4}]")
                }
            });
            if count {
                format!("{ours:<16} {reference:<17}")
            } else {
                format!("{ours:<15} {reference:<17}")
            }
        }
    }
}

fn csv_fields(cell: &Cell, kind: &Kind) -> Vec<String> {
    let number = field;
    match cell {
        Cell::Text(t) => vec![t.clone()],
        Cell::Composed { fields, .. } => fields.clone(),
        Cell::Number(v) => vec![number(*v)],
        Cell::Spread {
            ours,
            folds,
            thesis,
        } => {
            let mut fields = vec![
                ours.map_or_else(String::new, |m| number(m.mean)),
                ours.filter(|_| spread_shown(*folds))
                    .map_or_else(String::new, |m| number(m.std)),
            ];
            if matches!(
                kind,
                Kind::Error { thesis: true } | Kind::Count { thesis: true }
            ) {
                fields.push(thesis.map_or_else(String::new, |t| number(t.0)));
                fields.push(thesis.map_or_else(String::new, |t| number(t.1)));
            }
            fields
        }
    }
}

/// A field quoted where CSV needs it.
fn quoted(field: &str) -> String {
    if field.contains([',', '"', '\n']) {
        format!("\"{}\"", field.replace('"', "\"\""))
    } else {
        field.to_owned()
    }
}

/// One printed table.
#[derive(Clone, Debug)]
pub struct Table {
    /// The CSV file's name after the document's stem ("learning-curve").
    pub name: String,
    /// The lines printed above it.
    pub title: Vec<String>,
    pub columns: Vec<Column>,
    pub rows: Vec<Vec<Cell>>,
    /// Lines printed below it (summaries; not in the CSV).
    pub footer: Vec<String>,
}

impl Table {
    #[must_use]
    pub fn new(name: impl Into<String>, title: impl Into<String>, columns: Vec<Column>) -> Self {
        Self {
            name: name.into(),
            title: vec![title.into()],
            columns,
            rows: Vec::new(),
            footer: Vec::new(),
        }
    }

    fn line(&self, cells: impl Iterator<Item = String>) -> String {
        let line: Vec<String> = self
            .columns
            .iter()
            .zip(cells)
            .map(|(c, text)| {
                if c.right {
                    format!("{text:>w$}", w = c.width)
                } else {
                    format!("{text:<w$}", w = c.width)
                }
            })
            .collect();
        // Padding is for the columns that follow; none follows the last.
        line.join("  ").trim_end().to_owned()
    }

    /// The table as the terminal shows it, after an empty line.
    ///
    /// # Errors
    /// Writing to `out`.
    pub fn write_text(&self, out: &mut impl Write) -> io::Result<()> {
        writeln!(out)?;
        for line in &self.title {
            writeln!(out, "{line}")?;
        }
        writeln!(
            out,
            "{}",
            self.line(self.columns.iter().map(|c| c.head.clone()))
        )?;
        for row in &self.rows {
            let cells = row
                .iter()
                .zip(&self.columns)
                .map(|(cell, c)| text(cell, &c.kind));
            writeln!(out, "{}", self.line(cells))?;
        }
        for line in &self.footer {
            writeln!(out, "{line}")?;
        }
        Ok(())
    }

    /// The table as CSV: a header row with units, then one row per row.
    #[must_use]
    pub fn csv(&self) -> String {
        let mut text = String::new();
        let (head, rows) = self.csv_fields();
        for fields in std::iter::once(head).chain(rows) {
            let fields: Vec<String> = fields.iter().map(|f| quoted(f)).collect();
            text.push_str(&fields.join(","));
            text.push('\n');
        }
        text
    }

    /// The CSV's fields unquoted: the header row, then one row per row.
    #[must_use]
    pub fn csv_fields(&self) -> (Vec<String>, Vec<Vec<String>>) {
        let head = self.columns.iter().flat_map(Column::csv_heads).collect();
        let rows = self
            .rows
            .iter()
            .map(|row| {
                row.iter()
                    .zip(&self.columns)
                    .flat_map(|(cell, c)| csv_fields(cell, &c.kind))
                    .collect()
            })
            .collect();
        (head, rows)
    }
}

/// What is printed for one document: lines before the tables, the tables,
/// and lines after them.
#[derive(Clone, Debug, Default)]
pub struct Printout {
    /// Prefix of the CSV files' names ("push-task-gate-random").
    pub stem: String,
    pub head: Vec<String>,
    pub tables: Vec<Table>,
    pub foot: Vec<String>,
}

impl Printout {
    /// The text `pushlearn experiment` prints.
    ///
    /// # Errors
    /// Writing to `out`.
    pub fn write_text(&self, out: &mut impl Write) -> io::Result<()> {
        for line in &self.head {
            writeln!(out, "{line}")?;
        }
        for table in &self.tables {
            table.write_text(out)?;
        }
        for line in &self.foot {
            writeln!(out, "{line}")?;
        }
        Ok(())
    }

    /// Writes every table as `dir/STEM-NAME.csv`, each through a temporary
    /// file and a rename (an interrupted run leaves no half file), and
    /// returns the paths.
    ///
    /// # Errors
    /// A file cannot be written.
    pub fn write_csv(&self, dir: &Path) -> io::Result<Vec<PathBuf>> {
        self.tables
            .iter()
            .map(|t| {
                let path = dir.join(format!("{}-{}.csv", self.stem, t.name));
                write_atomically(&path, t.csv().as_bytes())?;
                Ok(path)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(folds: usize) -> Table {
        let mut t = Table::new(
            "curve",
            "A curve",
            vec![
                Column::new("N_train", 7, true, Kind::Text),
                Column::new(
                    "block position [m]",
                    33,
                    false,
                    Kind::Error { thesis: true },
                ),
                Column::new("x0 [m]", 7, true, Kind::Number { decimals: 3 }),
                Column::new("nodes", 16, false, Kind::Count { thesis: false }),
            ],
        );
        t.rows.push(vec![
            Cell::Text("3".into()),
            Cell::spread(
                MeanStd {
                    mean: 0.125,
                    std: 0.5,
                },
                folds,
                Some(Ms(0.1405, 0.1292)),
            ),
            Cell::Number(-0.35),
            Cell::spread(
                MeanStd {
                    mean: 12.0,
                    std: 1.5,
                },
                folds,
                None,
            ),
        ]);
        t.rows.push(vec![
            Cell::Text("a, \"b\"".into()),
            Cell::Spread {
                ours: None,
                folds,
                thesis: None,
            },
            Cell::Number(f64::NAN),
            Cell::spread(
                MeanStd {
                    mean: 1.0,
                    std: 0.0,
                },
                folds,
                None,
            ),
        ]);
        t
    }

    #[test]
    fn text_and_csv_come_from_the_same_cells() {
        let mut out = Vec::new();
        table(2).write_text(&mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(text.contains("0.1250 ± 0.5000 [0.1405 ± 0.1292]"), "{text}");
        assert!(text.contains("12.00 (1.50)"), "{text}");
        assert!(text.contains(" -0.350"), "{text}");
        let csv = table(2).csv();
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(
            lines[0],
            "N_train,block position mean [m],block position std [m],block position thesis mean [m],\
             block position thesis std [m],x0 [m],nodes mean,nodes std"
        );
        assert_eq!(lines[1], "3,0.125,0.5,0.1405,0.1292,-0.35,12,1.5");
        assert_eq!(lines[2], "\"a, \"\"b\"\"\",,,,,,1,0");
        assert_eq!(lines.len(), 3);
    }

    #[test]
    fn one_fold_shows_no_spread() {
        let mut out = Vec::new();
        table(1).write_text(&mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(!text.contains("0.1250 ±"), "{text}");
        assert!(text.contains("0.1250          [0.1405 ± 0.1292]"), "{text}");
        assert!(!text.contains("(1.50)") && text.contains("12.00"), "{text}");
        assert_eq!(
            table(1).csv().lines().nth(1),
            Some("3,0.125,,0.1405,0.1292,-0.35,12,")
        );
    }
}
