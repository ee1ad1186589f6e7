//! Argument values several command lines take, parsed one way: the
//! built-in models' options (clap's side of the model registry,
//! `learner::registry`, which holds the models, their options and their
//! checks), names, poses and actions. Shared by the application's commands
//! (the learner daemon's among them) and the experiments' arguments
//! (`lab::args`), which `pushlearn.bench` parses too.

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use learner::interaction::SelectorKind;
use learner::registry::{ConfigFlag, Improvement, ModelOptions, Named, Parts};
use learner::{Action, ObjectState};

/// A clap value parser for the names of `T`: `--help` lists each name with
/// its description, and clap refuses any other name as for a `ValueEnum`.
#[must_use]
pub fn named<T: Named + Send + Sync>() -> impl TypedValueParser<Value = T> {
    let values = T::ALL
        .iter()
        .map(|v| PossibleValue::new(v.name()).help(v.description()));
    PossibleValuesParser::new(values).try_map(|name: String| {
        // Unreachable: the possible values were checked before.
        T::from_name(&name).ok_or_else(|| format!("unknown name '{name}'"))
    })
}

/// The model options as `pushlearn experiment …` and `pushlearn learn`
/// take them, mapped onto the registry's [`ModelOptions`] one field each.
#[derive(Clone, Debug, Default, PartialEq, clap::Args)]
pub struct ModelArgs {
    /// Configuration number of the original: the sum of its bits (1
    /// USE_DYNS, 2 LOWFREQ, 4 ALLOWMISSPOSITIONS, 8 FIXFIRSTTHREETRAININGRUNS,
    /// 16 HARDCODEDACT, 32 HARDCODEDGATE, 64 USINGPREDICTIONBOOST).
    #[arg(long, value_name = "N", default_value_t = 0, value_parser = clap::value_parser!(u32).range(0..=i64::from(learner::flags::ALL)))]
    pub config: u32,

    /// Configuration bits by name, comma-separated; added to --config.
    #[arg(
        long = "flag",
        value_name = "FLAG,…",
        value_parser = named::<ConfigFlag>(),
        value_delimiter = ','
    )]
    pub flags: Vec<ConfigFlag>,

    /// Learning rate η (η_in = η_out = η_A) of the forward models: the gate
    /// model's actuator and block predictors, the interaction model's ACs.
    /// 0 in the final thesis; the draft's tables use 0.0, 0.1 and 0.2.
    #[arg(long, value_name = "ETA", default_value_t = 0.0, value_parser = parse_rate)]
    pub eta: f64,

    /// The interaction model's Abstract Collection Selector: aitm (final
    /// thesis), tree (the draft's decision tree, refitted on every stored
    /// reference), incremental-tree (Hoeffding tree, keeps no references) or
    /// nearest (the nearest stored reference: the draft's naive baseline).
    #[arg(long, value_name = "KIND", default_value = "aitm", value_parser = parse_selector)]
    pub selector: SelectorKind,

    /// With USE_DYNS, leave the block's angular velocity out (the draft's
    /// "NoAV" rows).
    #[arg(long)]
    pub no_angular_velocity: bool,

    /// Changes beyond the thesis for the gate model, comma-separated:
    /// unrounded, interpolate, adapt-actuator, average-outputs,
    /// forward-check, shared-blocks, or all (which
    /// is `--model gate+`). Not the thesis's model: reports name it
    /// `gate+CHANGE+…` (docs/models.md, "Beyond the thesis").
    #[arg(long, value_name = "CHANGE,…", value_parser = named::<Improvement>(), value_delimiter = ',')]
    pub improve: Vec<Improvement>,

    /// The parts of a model built of parts, for its ablation (the models'
    /// descriptions say which takes them): mechanics (the shape's mechanics
    /// alone, learning nothing), identified (their parameters identified
    /// online) or full (and the memory of their residual). Reports name a
    /// partial model `MODEL-PARTS`.
    #[arg(long, value_name = "PARTS", default_value = "full", value_parser = named::<Parts>())]
    pub parts: Parts,
}

impl ModelArgs {
    /// The options as the registry takes them.
    #[must_use]
    pub fn options(&self) -> ModelOptions {
        let ModelArgs {
            config,
            flags,
            eta,
            selector,
            no_angular_velocity,
            improve,
            parts,
        } = self.clone();
        ModelOptions {
            config,
            flags,
            eta,
            selector,
            no_angular_velocity,
            improve,
            parts,
        }
    }
}

/// Clap checks --eta as it parses it, so that the refusal quotes the text
/// given; options built otherwise are checked by the registry.
fn parse_rate(text: &str) -> Result<f64, String> {
    text.parse::<f64>()
        .ok()
        .filter(|v| learner::registry::is_learning_rate(*v))
        .ok_or_else(|| format!("'{text}' is not a finite, non-negative number"))
}

fn parse_selector(text: &str) -> Result<SelectorKind, String> {
    learner::registry::selector(text).map_err(|e| e.to_string())
}

/// `X,Y,ORI` as three finite numbers.
pub fn parse_pose(text: &str) -> Result<ObjectState, String> {
    let v = parse_numbers(text, 3)?;
    Ok(ObjectState::new(v[0], v[1], v[2]))
}

/// `n` comma-separated finite numbers.
fn parse_numbers(text: &str, n: usize) -> Result<Vec<f64>, String> {
    let v: Vec<f64> = text
        .split(',')
        .map(|s| {
            s.trim()
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| format!("'{s}' is not a finite number"))
        })
        .collect::<Result<_, _>>()?;
    if v.len() == n {
        Ok(v)
    } else {
        Err(format!(
            "expected {n} comma-separated numbers, got {}",
            v.len()
        ))
    }
}

/// `VX,VY` as two finite numbers.
pub fn parse_action(text: &str) -> Result<Action, String> {
    let v = parse_numbers(text, 2)?;
    Ok(Action::new(v[0], v[1]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use learner::registry::ModelKind;

    #[test]
    fn poses_and_actions_parse_strictly() {
        assert_eq!(parse_action("0,-0.5"), Ok(Action::new(0.0, -0.5)));
        assert!(parse_action("0,0,0").is_err());
        assert_eq!(
            parse_pose("-0.6, 0.7,0.75"),
            Ok(ObjectState::new(-0.6, 0.7, 0.75))
        );
        assert!(parse_pose("1,2").unwrap_err().contains("expected 3"));
        assert!(parse_pose("1,nan,2").unwrap_err().contains("finite"));
        assert!(parse_pose("1,x,2").is_err());
        assert_eq!(parse_numbers("0,0.5", 2), Ok(vec![0.0, 0.5]));
    }

    #[derive(clap::Parser)]
    struct Cli {
        #[arg(long, value_parser = named::<ModelKind>(), default_value_t = ModelKind::Gate)]
        model: ModelKind,
        #[command(flatten)]
        options: ModelArgs,
    }

    fn parse(args: &[&str]) -> Result<Cli, clap::Error> {
        let mut argv = vec!["test"];
        argv.extend_from_slice(args);
        <Cli as clap::Parser>::try_parse_from(argv)
    }

    fn options(args: &[&str]) -> ModelOptions {
        parse(args).expect("valid options").options.options()
    }

    #[test]
    fn no_flags_are_the_registrys_defaults() {
        let cli = parse(&[]).unwrap();
        assert_eq!(cli.model, ModelKind::Gate);
        assert_eq!(cli.options.options(), ModelOptions::default());
    }

    #[test]
    fn every_flag_maps_onto_its_field() {
        let o = options(&[
            "--config",
            "8",
            "--flag",
            "hard-coded-gate,use-dyns",
            "--eta",
            "0.1",
            "--selector",
            "tree",
            "--no-angular-velocity",
            "--improve",
            "forward-check,unrounded",
            "--parts",
            "identified",
        ]);
        assert_eq!(
            o,
            ModelOptions {
                config: 8,
                flags: vec![ConfigFlag::HardCodedGate, ConfigFlag::UseDyns],
                eta: 0.1,
                selector: SelectorKind::Tree,
                no_angular_velocity: true,
                improve: vec![Improvement::ForwardCheck, Improvement::Unrounded],
                parts: Parts::Identified,
            }
        );
        for kind in ModelKind::ALL {
            assert_eq!(parse(&["--model", kind.name()]).unwrap().model, *kind);
        }
        assert_eq!(
            options(&["--improve", "all"]).improve,
            vec![Improvement::All]
        );
    }

    #[test]
    fn bad_values_are_refused_as_they_are_parsed() {
        for bad in [
            &["--eta", "-1"][..],
            &["--eta", "nan"],
            &["--config", "128"],
            &["--selector", "forest"],
            &["--flag", "turbo"],
            &["--improve", "turbo"],
            &["--model", "GATE"],
            &["--model", "gate+unrounded"],
        ] {
            assert!(parse(bad).is_err(), "{bad:?}");
        }
        let err = parse(&["--selector", "forest"]).err().unwrap().to_string();
        assert!(
            err.contains(
                "unknown selector 'forest'; one of: aitm, tree, incremental-tree, nearest"
            ),
            "{err}"
        );
    }
}
