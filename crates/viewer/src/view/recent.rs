//! Recently opened files, most recent first, kept in the preferences (`Prefs::recent`): one entry per file
//! (compared by canonical path), at most `CAP`. Pure functions, so the list's rules are unit tested.
use std::path::{Path, PathBuf};

/// The most files the list keeps.
pub const CAP: usize = 10;

/// The path the list keeps for `spec`: its canonical path when it names an existing file, else None
/// (generator specs such as `gen:city` and missing files are not remembered).
pub fn entry_for(spec: &str) -> Option<PathBuf> {
    let p = Path::new(spec);
    p.is_file().then(|| std::fs::canonicalize(p).ok()).flatten()
}

/// `path` becomes the first entry: an older entry for the same file (same canonical path) is dropped and the
/// list is cut at `cap`.
pub fn push(list: &mut Vec<PathBuf>, path: PathBuf, cap: usize) {
    let key = canonical(&path);
    list.retain(|p| canonical(p) != key);
    list.insert(0, path);
    list.truncate(cap);
}

/// A list read from a preferences file: relative paths and repeats dropped, cut at `cap` (missing files stay,
/// shown disabled: a drive may be unmounted).
pub fn sanitize(list: &mut Vec<PathBuf>, cap: usize) {
    let mut seen = Vec::new();
    list.retain(|p| {
        let key = canonical(p);
        let keep = p.is_absolute() && !seen.contains(&key);
        seen.push(key);
        keep
    });
    list.truncate(cap);
}

/// The entries as the menu shows them: the path and whether the file is there to open.
pub fn entries(list: &[PathBuf]) -> Vec<(PathBuf, bool)> {
    list.iter().map(|p| (p.clone(), p.is_file())).collect()
}

fn canonical(p: &Path) -> PathBuf {
    std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn most_recent_first_deduplicated_and_capped() {
        let dir = std::env::temp_dir().join(format!("hrtao-recent-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        let file = |n: &str| {
            let p = dir.join(n);
            std::fs::write(&p, "v 0 0 0\n").unwrap();
            p
        };
        let (a, b) = (file("a.obj"), file("b.obj"));
        let mut list = Vec::new();
        push(&mut list, a.clone(), 3);
        push(&mut list, b.clone(), 3);
        assert_eq!(list, vec![b.clone(), a.clone()], "most recent first");
        // The same file by another spelling is one entry, moved to the front.
        push(&mut list, dir.join("sub/../a.obj"), 3);
        assert_eq!(list.len(), 2);
        assert_eq!(canonical(&list[0]), canonical(&a));
        assert_eq!(list[1], b);
        for n in ["c.obj", "d.obj", "e.obj"] {
            let p = file(n);
            push(&mut list, p, 3);
        }
        assert_eq!(list.len(), 3, "capped");
        assert_eq!(list[0], dir.join("e.obj"));
        // Only existing files are remembered; generator specs are not files.
        assert_eq!(entry_for("gen:city"), None);
        assert_eq!(entry_for(dir.join("missing.obj").to_str().unwrap()), None);
        assert_eq!(entry_for(a.to_str().unwrap()), Some(canonical(&a)));
        // A missing file stays in the list, disabled.
        std::fs::remove_file(dir.join("d.obj")).unwrap();
        let shown = entries(&list);
        assert_eq!(shown[1], (dir.join("d.obj"), false));
        assert!(shown[0].1);
        // A hand-edited list: relative paths and repeats go, the cap holds.
        let mut read = vec![
            PathBuf::from("relative.obj"),
            a.clone(),
            dir.join("sub/../a.obj"),
            b.clone(),
            dir.join("c.obj"),
        ];
        sanitize(&mut read, 2);
        assert_eq!(read, vec![a, b]);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
