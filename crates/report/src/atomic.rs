//! Files replaced whole: written beside their place under a temporary name, synced, and
//! renamed over it, so a process stopped at any moment leaves the old file or the new one,
//! never one cut short. The run directories' records and checkpoint, and the report's
//! pages and plots, are written this way.

use std::path::{Path, PathBuf};

/// Write `bytes` to `path` through `<path>.tmp` and a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    {
        use std::io::Write;
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        // The data must be on disk before the rename makes it the file.
        f.sync_all()?;
    }
    std::fs::rename(&tmp, path)
}

/// Where to draw a file that will replace `path` whole ([`finish`] renames it): the same
/// directory, a hidden name, the same extension (image encoders choose the format by it).
pub fn staging_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.tmp.{}", extension(path)))
}

/// Renames the file drawn at [`staging_path`] over `path`.
pub fn finish(path: &Path) -> std::io::Result<()> {
    std::fs::rename(staging_path(path), path)
}

fn extension(path: &Path) -> String {
    path.extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_staged_file_keeps_its_extension_and_replaces_the_old_one() {
        let dir = crate::synthetic::TempDir::new("atomic");
        let png = dir.path().join("returns.png");
        assert_eq!(staging_path(&png), dir.path().join(".returns.png.tmp.png"));
        std::fs::write(&png, "old").unwrap();
        std::fs::write(staging_path(&png), "new").unwrap();
        finish(&png).unwrap();
        assert_eq!(std::fs::read_to_string(&png).unwrap(), "new");
        write_atomic(&png, b"newer").unwrap();
        assert_eq!(std::fs::read_to_string(&png).unwrap(), "newer");
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(left.len(), 1, "temporary files left: {left:?}");
    }
}
