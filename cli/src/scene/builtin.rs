//! The built-in scenes: their names and TOML texts (the files in `cli/scenes/`).

/// The built-in scenes, as (name, TOML text).
pub const BUILTIN_SCENES: &[(&str, &str)] = &[
    ("oscillator", include_str!("../../scenes/oscillator.toml")),
    ("kepler", include_str!("../../scenes/kepler.toml")),
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
        "oscillator-beyond-stability",
        include_str!("../../scenes/oscillator-beyond-stability.toml"),
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
