//! A merged sweep in one table: per configuration and N_train, each seed's
//! learning-curve errors. It is what `merged/summary.md` and `summary.csv`
//! show, and the document `pushlearn reproduce` keeps of a sweep
//! (`docs/results/ablation.json`), small enough to commit where the
//! per-seed reports are not.

use std::fmt::Write as _;

use serde::{Deserialize, Serialize};

use super::{Configuration, Sweep};
use drive::results::PushReport;

/// One sweep's errors, row by row.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// The plan's shape (`19 configurations × 3 seeds × … = 4560 jobs`).
    pub shape: String,
    pub seeds: Vec<u64>,
    pub folds: usize,
    /// In the plan's order: configuration, then N_train.
    pub rows: Vec<Row>,
}

/// One configuration at one number of training runs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// The configuration's id (the jobs' `CONFIG`).
    pub configuration: String,
    /// Its options as [`Configuration::label`] writes them.
    pub options: String,
    /// The model's name as the reports give it (`gate`, `interaction`, …).
    pub model: String,
    pub train_runs: usize,
    /// One entry per seed, in the order the seeds were added.
    pub seeds: Vec<SeedErrors>,
}

/// A seed's learning-curve errors of the blue block and the actuator, each
/// the mean over its folds and test positions.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SeedErrors {
    pub seed: u64,
    pub block_pos_err: f64,
    pub block_ori_err: f64,
    pub actuator_pos_err: f64,
}

/// Which error of a [`SeedErrors`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metric {
    BlockPosition,
    BlockOrientation,
    Actuator,
}

impl Metric {
    pub const ALL: [Metric; 3] = [
        Metric::BlockPosition,
        Metric::BlockOrientation,
        Metric::Actuator,
    ];

    fn of(self, errors: &SeedErrors) -> f64 {
        match self {
            Metric::BlockPosition => errors.block_pos_err,
            Metric::BlockOrientation => errors.block_ori_err,
            Metric::Actuator => errors.actuator_pos_err,
        }
    }

    fn csv_name(self) -> &'static str {
        match self {
            Metric::BlockPosition => "block_pos_err",
            Metric::BlockOrientation => "block_ori_err",
            Metric::Actuator => "actuator_pos_err",
        }
    }
}

impl Row {
    /// The mean over seeds of `metric`, and the spread (population standard
    /// deviation) of the seeds' values around it.
    #[must_use]
    pub fn mean_spread(&self, metric: Metric) -> (f64, f64) {
        let n = self.seeds.len() as f64;
        let mean = self.seeds.iter().map(|s| metric.of(s)).sum::<f64>() / n;
        let var = self
            .seeds
            .iter()
            .map(|s| (metric.of(s) - mean).powi(2))
            .sum::<f64>()
            / n;
        (mean, var.sqrt())
    }
}

/// A configuration by what it changes against its model's defaults: its
/// options without the model (`flag=use-dyns`), `defaults` for none.
#[must_use]
pub fn change_label(options: &str) -> String {
    let changes: Vec<&str> = options
        .split(' ')
        .filter(|o| !o.starts_with("model=") && *o != "(defaults)")
        .collect();
    if changes.is_empty() {
        DEFAULTS.to_owned()
    } else {
        changes.join(" ")
    }
}

/// [`change_label`] of a configuration that sets nothing but the model.
pub const DEFAULTS: &str = "defaults";

impl Summary {
    /// The id of `model`'s configuration that changes nothing, if the sweep
    /// has one.
    #[must_use]
    pub fn defaults_of(&self, model: &str) -> Option<&str> {
        self.configurations()
            .into_iter()
            .find(|(_, options, m)| *m == model && change_label(options) == DEFAULTS)
            .map(|(id, ..)| id)
    }

    /// An empty summary of `sweep`'s plan.
    #[must_use]
    pub fn new(sweep: &Sweep) -> Self {
        Self {
            shape: sweep.shape(),
            seeds: sweep.seeds.clone(),
            folds: sweep.folds,
            rows: Vec::new(),
        }
    }

    /// Adds `report`, the merged report of `configuration` under `seed`.
    pub fn add(&mut self, configuration: &Configuration, seed: u64, report: &PushReport) {
        for entry in &report.results {
            let errors = SeedErrors {
                seed,
                block_pos_err: entry.blue.block_pos_err.mean,
                block_ori_err: entry.blue.block_ori_err.mean,
                actuator_pos_err: entry.blue.actuator_pos_err.mean,
            };
            let found = self
                .rows
                .iter_mut()
                .find(|r| r.configuration == configuration.id && r.train_runs == entry.train_runs);
            match found {
                Some(row) => row.seeds.push(errors),
                None => self.rows.push(Row {
                    configuration: configuration.id.clone(),
                    options: configuration.label(),
                    model: report.setup.model.clone(),
                    train_runs: entry.train_runs,
                    seeds: vec![errors],
                }),
            }
        }
    }

    /// The training-run counts, in the rows' order of first appearance.
    #[must_use]
    pub fn train_runs(&self) -> Vec<usize> {
        let mut runs: Vec<usize> = Vec::new();
        for row in &self.rows {
            if !runs.contains(&row.train_runs) {
                runs.push(row.train_runs);
            }
        }
        runs
    }

    /// The configurations (id, options, model) in the rows' order.
    #[must_use]
    pub fn configurations(&self) -> Vec<(&str, &str, &str)> {
        let mut seen: Vec<(&str, &str, &str)> = Vec::new();
        for row in &self.rows {
            if !seen.iter().any(|(id, ..)| *id == row.configuration) {
                seen.push((&row.configuration, &row.options, &row.model));
            }
        }
        seen
    }

    /// The row of configuration `id` at `train_runs`.
    #[must_use]
    pub fn row(&self, id: &str, train_runs: usize) -> Option<&Row> {
        self.rows
            .iter()
            .find(|r| r.configuration == id && r.train_runs == train_runs)
    }

    /// `merged/summary.md`: one line per row, mean ± spread over seeds.
    #[must_use]
    pub fn markdown(&self) -> String {
        let mut s = format!(
            "{}.\n\nMeans over the {} seeds (± their spread) of the learning curves' mean errors of the blue block (position in m, orientation in rad) and of the actuator (m); each seed's value is over its {} folds.\n\n",
            self.shape,
            self.seeds.len(),
            self.folds
        );
        s.push_str("| configuration | options | model | N_train | block position | block orientation | actuator |\n");
        s.push_str("|---|---|---|--:|--:|--:|--:|\n");
        for row in &self.rows {
            let _ = write!(
                s,
                "| {} | {} | {} | {} |",
                row.configuration, row.options, row.model, row.train_runs
            );
            for metric in Metric::ALL {
                let (mean, spread) = row.mean_spread(metric);
                let _ = write!(s, " {mean:.4} ± {spread:.4} |");
            }
            s.push('\n');
        }
        s
    }

    /// `merged/summary.csv`: the same rows, full precision.
    #[must_use]
    pub fn csv(&self) -> String {
        let mut s = String::from("configuration,options,model,train_runs,seeds");
        for metric in Metric::ALL {
            let _ = write!(s, ",{0},{0}_spread", metric.csv_name());
        }
        s.push('\n');
        for row in &self.rows {
            let _ = write!(
                s,
                "{},\"{}\",{},{},{}",
                row.configuration,
                row.options,
                row.model,
                row.train_runs,
                row.seeds.len()
            );
            for metric in Metric::ALL {
                let (mean, spread) = row.mean_spread(metric);
                let _ = write!(s, ",{mean},{spread}");
            }
            s.push('\n');
        }
        s
    }

    /// Pretty JSON, one trailing newline (as the reports are written).
    ///
    /// # Errors
    /// Serialisation failed (not expected for these types).
    pub fn to_json(&self) -> Result<String, serde_json::Error> {
        let mut text = serde_json::to_string_pretty(self)?;
        text.push('\n');
        Ok(text)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn errors(seed: u64, pos: f64) -> SeedErrors {
        SeedErrors {
            seed,
            block_pos_err: pos,
            block_ori_err: 2.0 * pos,
            actuator_pos_err: 0.001,
        }
    }

    fn summary() -> Summary {
        Summary {
            shape: "2 configurations × 2 seeds × 2 training-run counts × 2 folds = 16 jobs".into(),
            seeds: vec![1, 2],
            folds: 2,
            rows: vec![
                Row {
                    configuration: "aaaaaaaaaaaa".into(),
                    options: "model=gate".into(),
                    model: "gate".into(),
                    train_runs: 1,
                    seeds: vec![errors(1, 0.1), errors(2, 0.3)],
                },
                Row {
                    configuration: "aaaaaaaaaaaa".into(),
                    options: "model=gate".into(),
                    model: "gate".into(),
                    train_runs: 3,
                    seeds: vec![errors(1, 0.05), errors(2, 0.05)],
                },
                Row {
                    configuration: "bbbbbbbbbbbb".into(),
                    options: "eta=0.1 model=gate".into(),
                    model: "gate".into(),
                    train_runs: 1,
                    seeds: vec![errors(1, 0.2), errors(2, 0.2)],
                },
            ],
        }
    }

    #[test]
    fn the_mean_and_spread_are_over_seeds() {
        let s = summary();
        let (mean, spread) = s.rows[0].mean_spread(Metric::BlockPosition);
        assert!((mean - 0.2).abs() < 1e-12, "{mean}");
        assert!((spread - 0.1).abs() < 1e-12, "{spread}");
        let (mean, spread) = s.rows[0].mean_spread(Metric::BlockOrientation);
        assert!((mean - 0.4).abs() < 1e-12 && (spread - 0.2).abs() < 1e-12);
        assert_eq!(s.rows[1].mean_spread(Metric::Actuator), (0.001, 0.0));
    }

    #[test]
    fn configurations_and_training_runs_keep_the_rows_order() {
        let s = summary();
        assert_eq!(s.train_runs(), [1, 3]);
        assert_eq!(
            s.configurations(),
            [
                ("aaaaaaaaaaaa", "model=gate", "gate"),
                ("bbbbbbbbbbbb", "eta=0.1 model=gate", "gate")
            ]
        );
        assert_eq!(s.row("bbbbbbbbbbbb", 1).map(|r| r.seeds.len()), Some(2));
        assert!(s.row("bbbbbbbbbbbb", 3).is_none());
        assert_eq!(s.defaults_of("gate"), Some("aaaaaaaaaaaa"));
        assert_eq!(s.defaults_of("interaction"), None);
        assert_eq!(change_label("(defaults)"), "defaults");
        assert_eq!(change_label("eta=0.1 model=gate"), "eta=0.1");
    }

    #[test]
    fn the_tables_and_the_document_carry_every_row() {
        let s = summary();
        let md = s.markdown();
        assert!(md.contains("| aaaaaaaaaaaa | model=gate | gate | 1 | 0.2000 ± 0.1000 | 0.4000 ± 0.2000 | 0.0010 ± 0.0000 |"), "{md}");
        assert_eq!(md.lines().filter(|l| l.starts_with("| ")).count(), 4);
        let csv = s.csv();
        assert_eq!(csv.lines().count(), 4);
        assert!(csv.starts_with(
            "configuration,options,model,train_runs,seeds,block_pos_err,block_pos_err_spread,"
        ));
        let back: Summary = serde_json::from_str(&s.to_json().unwrap()).unwrap();
        assert_eq!(back, s);
    }
}
