//! The hybrid model's options: its checks and its constructor from the
//! registry's [`ModelOptions`], its parts by name and the names reports
//! give a model of some parts.

use crate::hybrid::{HybridConfig, Parts};
use crate::registry::{ModelKind, ModelOptions, ModelOptionsError, Named};

impl Named for Parts {
    const ALL: &'static [Self] = &Parts::ALL;

    fn name(self) -> &'static str {
        self.as_str()
    }

    fn description(self) -> &'static str {
        match self {
            Parts::Mechanics => {
                "the mechanics alone, with the parameters the shape suggests; learns nothing"
            }
            Parts::Identified => "the mechanics with parameters identified from the messages",
            Parts::Full => "the identified mechanics and the memory of their residual",
        }
    }
}

impl ModelOptions {
    /// The hybrid model's configuration. It has no thesis variants: the
    /// configuration bits of the model (1, 16, 32, 64), --eta, --selector,
    /// --no-angular-velocity and --improve are refused.
    ///
    /// # Errors
    /// The first option that does not apply, named.
    pub fn hybrid(&self, publish_rate_hz: u32) -> Result<HybridConfig, ModelOptionsError> {
        if let Some(option) = self.thesis_model_option() {
            return Err(ModelOptionsError::ThesisOptionOnModel {
                option,
                model: ModelKind::Hybrid,
            });
        }
        Ok(HybridConfig {
            parts: self.parts,
            publish_rate_hz,
        })
    }

    /// The name reports give the hybrid model of these parts: `hybrid`, or
    /// `hybrid-PARTS` for a part of it.
    pub(crate) fn hybrid_report_name(&self) -> String {
        if self.parts == Parts::Full {
            ModelKind::Hybrid.as_str().to_owned()
        } else {
            format!("{}-{}", ModelKind::Hybrid.as_str(), self.parts.as_str())
        }
    }
}

/// Whether `name` is a name [`ModelOptions::hybrid_report_name`] gives a
/// model of some of the parts (`hybrid-full` is not: that is `hybrid`).
pub(crate) fn is_partial_report_name(name: &str) -> bool {
    name.strip_prefix(ModelKind::Hybrid.as_str())
        .and_then(|rest| rest.strip_prefix('-'))
        .is_some_and(|parts| {
            Parts::ALL
                .iter()
                .any(|p| *p != Parts::Full && p.as_str() == parts)
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hybrid_model_refuses_the_thesis_models_options_and_only_it_takes_parts() {
        let parts = ModelOptions {
            parts: Parts::Mechanics,
            ..ModelOptions::default()
        };
        assert_eq!(parts.hybrid(100).unwrap().parts, Parts::Mechanics);
        assert_eq!(parts.report_name(ModelKind::Hybrid), "hybrid-mechanics");
        assert_eq!(
            ModelKind::of_report_name("hybrid-mechanics"),
            Some(ModelKind::Hybrid)
        );
        assert_eq!(ModelKind::of_report_name("hybrid-full"), None);
        assert!(matches!(
            parts.gate(100),
            Err(ModelOptionsError::PartsNotForModel(ModelKind::Gate))
        ));
        assert!(parts.check_external().is_err());
        let eta = ModelOptions {
            eta: 0.1,
            ..ModelOptions::default()
        };
        let bits = ModelOptions {
            config: 16 | 8,
            ..ModelOptions::default()
        };
        for (options, named) in [
            (eta, "--eta"),
            (bits, "configuration bits 16 (of --config/--flag)"),
        ] {
            match options.hybrid(100) {
                Err(ModelOptionsError::ThesisOptionOnModel {
                    option,
                    model: ModelKind::Hybrid,
                }) => {
                    assert_eq!(option, named);
                }
                other => panic!("{other:?}"),
            }
        }
        // The driver's bits apply to any learner.
        let driver = ModelOptions {
            config: 2 | 4 | 8,
            ..ModelOptions::default()
        };
        assert!(driver.hybrid(10).is_ok() && driver.check_external().is_ok());
    }
}
