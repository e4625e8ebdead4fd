//! The built-in scenes: their names and TOML texts (the files in `cli/scenes/`).
//!
//! To add one: write `cli/scenes/NAME.toml` (its first line, a `#` comment, is what `svi
//! list` shows) and add `("NAME", include_str!(...))` to [`BUILTIN_SCENES`]. Whether it runs
//! on ℝᴺ or a Lie group follows from its model.

/// The built-in scenes, as (name, TOML text): the scenes on ℝᴺ, the chains of runtime
/// dimension, then the rigid bodies on SO(3) and the models on the other Lie groups.
pub const BUILTIN_SCENES: &[(&str, &str)] = &[
    ("oscillator", include_str!("../../scenes/oscillator.toml")),
    ("kepler", include_str!("../../scenes/kepler.toml")),
    ("kepler-text", include_str!("../../scenes/kepler-text.toml")),
    (
        "kepler-h-text",
        include_str!("../../scenes/kepler-h-text.toml"),
    ),
    ("pendulum", include_str!("../../scenes/pendulum.toml")),
    (
        "spring-pendulum",
        include_str!("../../scenes/spring-pendulum.toml"),
    ),
    (
        "double-pendulum",
        include_str!("../../scenes/double-pendulum.toml"),
    ),
    (
        "damped-oscillator",
        include_str!("../../scenes/damped-oscillator.toml"),
    ),
    (
        "damped-pendulum",
        include_str!("../../scenes/damped-pendulum.toml"),
    ),
    (
        "driven-oscillator",
        include_str!("../../scenes/driven-oscillator.toml"),
    ),
    (
        "stiff-spring-pendulum",
        include_str!("../../scenes/stiff-spring-pendulum.toml"),
    ),
    (
        "stiff-spring-pendulum-coarse",
        include_str!("../../scenes/stiff-spring-pendulum-coarse.toml"),
    ),
    (
        "stiff-spring-pendulum-multiscale",
        include_str!("../../scenes/stiff-spring-pendulum-multiscale.toml"),
    ),
    ("kepler-long", include_str!("../../scenes/kepler-long.toml")),
    ("kepler-e0.9", include_str!("../../scenes/kepler-e0.9.toml")),
    (
        "kepler-e0.99",
        include_str!("../../scenes/kepler-e0.99.toml"),
    ),
    (
        "kepler-recovery",
        include_str!("../../scenes/kepler-recovery.toml"),
    ),
    (
        "double-pendulum-chaotic",
        include_str!("../../scenes/double-pendulum-chaotic.toml"),
    ),
    (
        "henon-heiles",
        include_str!("../../scenes/henon-heiles.toml"),
    ),
    (
        "restricted-three-body",
        include_str!("../../scenes/restricted-three-body.toml"),
    ),
    ("kepler-h", include_str!("../../scenes/kepler-h.toml")),
    ("pendulum-h", include_str!("../../scenes/pendulum-h.toml")),
    (
        "henon-heiles-h",
        include_str!("../../scenes/henon-heiles-h.toml"),
    ),
    (
        "magnetic-bottle",
        include_str!("../../scenes/magnetic-bottle.toml"),
    ),
    (
        "oscillator-beyond-stability",
        include_str!("../../scenes/oscillator-beyond-stability.toml"),
    ),
    (
        "outer-solar-system",
        include_str!("../../scenes/outer-solar-system.toml"),
    ),
    (
        "spherical-pendulum",
        include_str!("../../scenes/spherical-pendulum.toml"),
    ),
    (
        "double-pendulum-cartesian",
        include_str!("../../scenes/double-pendulum-cartesian.toml"),
    ),
    (
        "four-bar-linkage",
        include_str!("../../scenes/four-bar-linkage.toml"),
    ),
    ("fput", include_str!("../../scenes/fput.toml")),
    ("fput-text", include_str!("../../scenes/fput-text.toml")),
    ("fput-stiff", include_str!("../../scenes/fput-stiff.toml")),
    ("toda", include_str!("../../scenes/toda.toml")),
    (
        "relativistic-chain",
        include_str!("../../scenes/relativistic-chain.toml"),
    ),
    (
        "sine-gordon-chain",
        include_str!("../../scenes/sine-gordon-chain.toml"),
    ),
    ("rigid-body", include_str!("../../scenes/rigid-body.toml")),
    ("heavy-top", include_str!("../../scenes/heavy-top.toml")),
    ("pendulum-3d", include_str!("../../scenes/pendulum-3d.toml")),
    (
        "falling-body",
        include_str!("../../scenes/falling-body.toml"),
    ),
    ("dual-spin", include_str!("../../scenes/dual-spin.toml")),
    (
        "spherical-chain",
        include_str!("../../scenes/spherical-chain.toml"),
    ),
];

/// The scene `svi run` runs when none is named.
pub const DEFAULT_SCENE: &str = "kepler";

/// Names of the built-in scenes.
pub fn builtin_scene_names() -> Vec<&'static str> {
    BUILTIN_SCENES.iter().map(|(name, _)| *name).collect()
}

/// The TOML text of a built-in scene.
pub fn builtin_scene(name: &str) -> Option<&'static str> {
    BUILTIN_SCENES
        .iter()
        .find(|(scene, _)| *scene == name)
        .map(|(_, text)| *text)
}
