//! The presets shipped inside the binary, so `weft record flag_on_car` works
//! from any directory. Their files live in `presets/`.

/// A shipped preset.
#[derive(Clone, Copy, Debug)]
pub struct Shipped {
    /// Its name (the file stem).
    pub name: &'static str,
    /// Its TOML text.
    pub text: &'static str,
}

macro_rules! shipped {
    ($($name:literal),* $(,)?) => {
        /// Every shipped preset, in the order `weft presets` lists them.
        pub const ALL: &[Shipped] = &[$(Shipped {
            name: $name,
            text: include_str!(concat!("../../../presets/", $name, ".toml")),
        }),*];
    };
}

shipped!(
    "flag_on_car",
    "windy_flag",
    "cape_runner",
    "hanging_sheet",
    "sphere_drape",
    "stress_jerk",
    "folding_sheet",
    "furling_banner",
);

/// The shipped preset called `name`.
pub fn find(name: &str) -> Option<&'static Shipped> {
    ALL.iter().find(|p| p.name == name)
}

impl Shipped {
    /// The preset's one-line description (its `description` key).
    pub fn description(&self) -> String {
        self.text
            .parse::<toml::Table>()
            .ok()
            .and_then(|t| {
                t.get("description")
                    .and_then(|d| d.as_str())
                    .map(str::to_string)
            })
            .unwrap_or_default()
    }
}
