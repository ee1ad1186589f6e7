//! The `sbatch` job-array script of `pushlearn sweep slurm`: array task i
//! runs the i-th chunk of a job list frozen at submission (so that jobs
//! finishing meanwhile do not shift the chunks), through the hidden
//! `pushlearn sweep task`. Slurm does the scheduling; nothing here does.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// What the script needs.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Script {
    /// The `pushlearn` binary the tasks run (on the cluster's shared disk).
    pub exe: PathBuf,
    /// The world daemon binary.
    pub sim_bin: PathBuf,
    /// The submission's copy of the plan.
    pub plan: PathBuf,
    /// The output directory.
    pub out: PathBuf,
    /// The submission's job list, one id a line.
    pub list: PathBuf,
    /// Jobs in the list.
    pub jobs: usize,
    /// Jobs per array task.
    pub chunk_size: usize,
    /// Where each task's log goes (`%A` the array's id, `%a` the task's).
    pub log: PathBuf,
    pub job_name: String,
    /// `--cpus-per-task`: the task's world processes.
    pub cpus_per_task: u32,
    /// At most this many tasks at once (`--array=…%N`).
    pub max_running: Option<u32>,
    pub partition: Option<String>,
    /// `--time`, as Slurm takes it (`MM`, `HH:MM:SS`, `D-HH`…).
    pub time: Option<String>,
    /// Further `#SBATCH` options, as given (`--mem=2G`, `--account=x`).
    pub extra: Vec<String>,
}

impl Script {
    /// The number of array tasks.
    #[must_use]
    pub fn tasks(&self) -> usize {
        self.jobs.div_ceil(self.chunk_size.max(1))
    }

    /// The script's text.
    #[must_use]
    pub fn text(&self) -> String {
        let mut s = String::from("#!/bin/sh\n");
        let _ = writeln!(
            s,
            "# Written by `pushlearn sweep slurm`: {} jobs of {} in {} array tasks of up to {}.\n\
             # Each task runs its chunk of the job list and skips the jobs whose output\n\
             # exists, so a requeued or resubmitted task does only what is left.",
            self.jobs,
            self.plan.display(),
            self.tasks(),
            self.chunk_size
        );
        let _ = writeln!(s, "#SBATCH --job-name={}", self.job_name);
        let mut array = format!("0-{}", self.tasks().saturating_sub(1));
        if let Some(n) = self.max_running {
            let _ = write!(array, "%{n}");
        }
        let _ = writeln!(s, "#SBATCH --array={array}");
        let _ = writeln!(s, "#SBATCH --ntasks=1");
        let _ = writeln!(s, "#SBATCH --cpus-per-task={}", self.cpus_per_task);
        let _ = writeln!(s, "#SBATCH --output={}", self.log.display());
        // A preempted task comes back; its finished jobs are kept.
        let _ = writeln!(s, "#SBATCH --requeue");
        if let Some(partition) = &self.partition {
            let _ = writeln!(s, "#SBATCH --partition={partition}");
        }
        if let Some(time) = &self.time {
            let _ = writeln!(s, "#SBATCH --time={time}");
        }
        for option in &self.extra {
            let _ = writeln!(s, "#SBATCH {option}");
        }
        let _ = writeln!(s, "set -eu");
        let _ = writeln!(
            s,
            "exec {} sweep task {} --out {} --list {} --chunk-size {} --index \"$SLURM_ARRAY_TASK_ID\" \\\n  --workers \"${{SLURM_CPUS_PER_TASK:-1}}\" --sim-bin {}",
            quote(&self.exe),
            quote(&self.plan),
            quote(&self.out),
            quote(&self.list),
            self.chunk_size,
            quote(&self.sim_bin),
        );
        s
    }
}

/// `path` in single quotes for `sh`.
fn quote(path: &Path) -> String {
    format!("'{}'", path.display().to_string().replace('\'', r"'\''"))
}

/// The ids of array task `index`'s chunk of `list` (one id a line).
#[must_use]
pub fn chunk(list: &str, chunk_size: usize, index: usize) -> Vec<&str> {
    list.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .skip(index.saturating_mul(chunk_size))
        .take(chunk_size)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn script() -> Script {
        Script {
            exe: "/opt/push learn/pushlearn".into(),
            sim_bin: "/opt/bin/pushlearn-sim".into(),
            plan: "/scratch/out/slurm/submit-1.toml".into(),
            out: "/scratch/out".into(),
            list: "/scratch/out/slurm/submit-1.jobs".into(),
            jobs: 25,
            chunk_size: 10,
            log: "/scratch/out/slurm/submit-1-%A_%a.log".into(),
            job_name: "pushlearn-sweep".into(),
            cpus_per_task: 2,
            max_running: Some(4),
            partition: Some("short".into()),
            time: Some("00:30:00".into()),
            extra: vec!["--mem=2G".into()],
        }
    }

    #[test]
    fn the_script_is_an_array_of_chunks_with_the_options_passed_through() {
        let s = script();
        assert_eq!(s.tasks(), 3);
        let text = s.text();
        for line in [
            "#SBATCH --array=0-2%4",
            "#SBATCH --cpus-per-task=2",
            "#SBATCH --partition=short",
            "#SBATCH --time=00:30:00",
            "#SBATCH --mem=2G",
            "#SBATCH --output=/scratch/out/slurm/submit-1-%A_%a.log",
            "exec '/opt/push learn/pushlearn' sweep task '/scratch/out/slurm/submit-1.toml' --out '/scratch/out' --list '/scratch/out/slurm/submit-1.jobs' --chunk-size 10 --index \"$SLURM_ARRAY_TASK_ID\" \\",
        ] {
            assert!(text.lines().any(|l| l == line), "no line {line:?} in\n{text}");
        }
        let bare = Script {
            partition: None,
            time: None,
            max_running: None,
            extra: Vec::new(),
            jobs: 10,
            ..s
        };
        let text = bare.text();
        assert!(text.contains("#SBATCH --array=0-0\n"), "{text}");
        assert!(!text.contains("--partition") && !text.contains("--time"));
        assert_eq!(quote(Path::new("it's")), r"'it'\''s'");
    }

    #[test]
    fn chunks_cover_the_list_once() {
        let list = "a\nb\nc\n\nd\ne\n";
        assert_eq!(chunk(list, 2, 0), ["a", "b"]);
        assert_eq!(chunk(list, 2, 2), ["e"]);
        assert!(chunk(list, 2, 3).is_empty());
        let all: Vec<&str> = (0..3).flat_map(|i| chunk(list, 2, i)).collect();
        assert_eq!(all, ["a", "b", "c", "d", "e"]);
    }
}
