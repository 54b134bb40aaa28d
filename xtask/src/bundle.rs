//! `cargo xtask bundle <package> [--release]`: builds the plugin and lays out the CLAP and VST3
//! bundles in `target/bundled/` with nice-plug-xtask (all `cargo build` options pass through).

use clap::Args;

#[derive(Debug, Args)]
pub struct BundleArgs {
    /// The package to bundle (javari), then any `cargo build` options (--release, ...).
    #[arg(
        value_name = "PACKAGE [CARGO OPTIONS]",
        trailing_var_arg = true,
        allow_hyphen_values = true
    )]
    pub args: Vec<String>,
}

/// `command` is `bundle` or `bundle-universal`, as nice-plug-xtask expects it first.
pub fn run(command: &str, args: BundleArgs) -> Result<(), Box<dyn std::error::Error>> {
    let raw = std::iter::once(command.to_string()).chain(args.args);
    nice_plug_xtask::main_with_args("cargo xtask", raw)?;
    Ok(())
}
