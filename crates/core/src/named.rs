//! Closed sets of values known by name: the models, their changes, the
//! timing modes, the push-task variants, the objects. The command line
//! builds its parsers and `--help` from them, the documents store the names,
//! and the Python arguments take them, so each set's names are written once.

/// A closed set of values known by name: the vocabulary of the command
/// line, the documents and the Python arguments.
pub trait Named: Copy + 'static {
    /// Every value, in the order lists (and `--help`) show them.
    const ALL: &'static [Self];

    /// The value's name.
    fn name(self) -> &'static str;

    /// What the value means, in one line (the command line's help on it).
    fn description(self) -> &'static str;

    /// The value called `name`, exactly (no case folding).
    #[must_use]
    fn from_name(name: &str) -> Option<Self> {
        Self::ALL.iter().copied().find(|v| v.name() == name)
    }

    /// Every name, comma-separated.
    #[must_use]
    fn names() -> String {
        let names: Vec<&str> = Self::ALL.iter().map(|v| v.name()).collect();
        names.join(", ")
    }
}
