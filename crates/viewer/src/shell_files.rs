//! `hrtao generate-shell-files DIR` (hidden): the shell completions and the man pages, generated from the command
//! line's own definition (the one `hrtao --help` prints), so they list the same commands, options, formats and
//! environment variables. packaging/install.sh runs it and installs what it writes.
use std::path::Path;

use anyhow::{Context, Result};
use clap_complete::Shell;

/// Writes DIR/hrtao.bash, DIR/_hrtao (zsh), DIR/hrtao.fish, and DIR/man1/hrtao.1 with a page per visible command
/// (`hrtao-render.1`, …).
pub fn write(mut cmd: clap::Command, dir: &Path) -> Result<()> {
    let man = dir.join("man1");
    std::fs::create_dir_all(&man).with_context(|| format!("cannot create {}", man.display()))?;
    clap_mangen::generate_to(cmd.clone(), &man)
        .with_context(|| format!("cannot write the man pages to {}", man.display()))?;
    for (shell, file) in [
        (Shell::Bash, "hrtao.bash"),
        (Shell::Zsh, "_hrtao"),
        (Shell::Fish, "hrtao.fish"),
    ] {
        let mut out = Vec::new();
        clap_complete::generate(shell, &mut cmd, "hrtao", &mut out);
        let path = dir.join(file);
        std::fs::write(&path, out).with_context(|| format!("cannot write {}", path.display()))?;
    }
    println!("wrote the completions and the man pages to {}", dir.display());
    Ok(())
}
