//! `cargo xtask bundle <package> [--release]`: builds the plugin and lays out the CLAP and VST3
//! bundles in `target/bundled/` with nice-plug-xtask (all `cargo build` options pass through).

pub fn run(raw: &[String]) -> Result<(), Box<dyn std::error::Error>> {
    // `raw` starts with the command word (`bundle`), as nice-plug-xtask expects.
    nice_plug_xtask::main_with_args("cargo xtask", raw.iter().cloned())?;
    Ok(())
}
