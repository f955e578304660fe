//! `radlab scenes` and `radlab methods`: what exists, with parameters and defaults.

use crate::methods::{self, ParamLine};

/// Each parameter on two lines: name, what it takes and its default; then its help.
fn print_params(params: &[ParamLine]) {
    for p in params {
        println!("    {:<22} {}; default {}", p.name, p.accepts(), p.default);
        println!("        {}", p.help);
    }
}

/// Lists the builtin scenes and the file formats.
pub fn scenes() {
    println!(
        "Scenes are files (.toml, .obj with .mtl, .ply, .off, .mgf; see scenes/README.md) or builtins:\n"
    );
    for b in radlab_scene::builtin::builtins() {
        println!("builtin:{}\n    {}", b.name, b.doc);
        for (name, default, doc) in b.params {
            println!("    {:<24} default {:<14} {}", name, default, doc);
        }
        println!();
    }
}

/// Lists the methods with their parameters.
pub fn methods() {
    println!("Methods (--method NAME; parameters with --set key=value):\n");
    for m in methods::methods() {
        println!("{}\n    {}", m.name, m.summary);
        print_params(&(m.params)());
        println!();
    }
    println!(
        "Each method's error and time at its defaults on a suite of scene kinds nobody tuned on \
         (experiments/defaults-suite.toml), and where the defaults fall short: docs/defaults.md."
    );
}
