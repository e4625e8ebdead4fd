//! Every file `svi` writes goes through here: checked before any work, written atomically.
//!
//! - **Checked first** ([`check_file`], [`check_directory`], [`check_distinct`]): an output is
//!   a regular file or a name that does not exist yet. A symbolic link, a directory, a FIFO or
//!   a device at that name is bad input, named before anything runs or is opened: svi never
//!   writes through a link (another user could have planted it) and never opens a FIFO (which
//!   blocks until a reader comes). Two outputs of one command may not be the same file, and
//!   no output may be the scene file it reads.
//! - **Written atomically** ([`OutputFile`]): the bytes go to a temporary file with an
//!   unguessable name, created exclusively (`O_EXCL`) beside the destination, which
//!   [`OutputFile::commit`] renames over it. A rename replaces the name itself, never the file
//!   a link there points to; an existing file is replaced only once the new one is complete,
//!   so a run that is killed, or fails before its outputs, leaves the old file as it was and
//!   no torn row. A temporary that is dropped uncommitted is removed; the binary removes those
//!   of a run stopped by Ctrl-C or SIGTERM ([`remove_pending`]).

use std::collections::BTreeSet;
use std::fs::Metadata;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// An output that cannot be used or written.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// A path that cannot be an output of `option` (bad input, named before any work).
    #[error("cannot write {option} to '{}': {reason}", path.display())]
    Unusable {
        /// The option, as written on the command line.
        option: &'static str,
        /// The path given.
        path: PathBuf,
        /// Why not.
        reason: String,
    },
    /// Standard output could not be written (a full device, a closed pipe).
    #[error("cannot write to standard output")]
    Stdout(#[source] io::Error),
    /// A file that could not be created or written.
    #[error("cannot write output file '{}'", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: io::Error,
    },
}

/// Write `text` to standard output and flush it: a full device or a closed pipe is an
/// [`OutputError::Stdout`], never a panic (`println!` panics).
pub fn print(text: impl std::fmt::Display) -> Result<(), OutputError> {
    let mut out = io::stdout().lock();
    write!(out, "{text}")
        .and_then(|()| out.flush())
        .map_err(OutputError::Stdout)
}

/// Write `text` and a newline to standard error. An error writing it is ignored: there is
/// nowhere left to report it (`eprintln!` panics).
pub fn warn(text: impl std::fmt::Display) {
    let mut err = io::stderr().lock();
    let _ = writeln!(err, "{text}").and_then(|()| err.flush());
}

impl OutputError {
    /// Whether the error is in the input (a path that cannot be an output) rather than in
    /// writing.
    pub fn is_bad_input(&self) -> bool {
        matches!(self, OutputError::Unusable { .. })
    }
}

/// What a file that is not a regular file is, in words.
pub fn file_kind(metadata: &Metadata) -> &'static str {
    let kind = metadata.file_type();
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if kind.is_char_device() {
            return "a character device";
        }
        if kind.is_block_device() {
            return "a block device";
        }
        if kind.is_socket() {
            return "a socket";
        }
    }
    if kind.is_symlink() {
        "a symbolic link (svi never writes through a link: remove it, or name the file it points to)"
    } else if kind.is_dir() {
        "a directory"
    } else {
        "not a regular file"
    }
}

/// The error of an output that cannot be used: bad input naming the option and the path.
fn unusable(option: &'static str, path: &Path, reason: impl Into<String>) -> OutputError {
    OutputError::Unusable {
        option,
        path: path.into(),
        reason: reason.into(),
    }
}

/// Check that `path` can be written as the output `option`: a name that does not exist yet,
/// or a regular file (which the output will replace), not a link, directory, FIFO or
/// device; a non-empty name with a file name.
pub fn check_file(option: &'static str, path: &Path) -> Result<(), OutputError> {
    if path.as_os_str().is_empty() {
        return Err(unusable(option, path, "the name is empty"));
    }
    // `-` is standard output to many tools; here it would be a file named `-` (and with
    // --json standard output holds the summary).
    if path.as_os_str() == "-" {
        return Err(unusable(
            option,
            path,
            "'-' would be a file of that name, not standard output: name the file",
        ));
    }
    if path.file_name().is_none() || path.as_os_str().to_string_lossy().ends_with('/') {
        return Err(unusable(option, path, "it names a directory, not a file"));
    }
    match std::fs::symlink_metadata(path) {
        Ok(metadata) if metadata.is_file() => Ok(()),
        Ok(metadata) => Err(unusable(
            option,
            path,
            format!("it is {}", file_kind(&metadata)),
        )),
        Err(error) if error.kind() == io::ErrorKind::NotFound => Ok(()),
        // Unreadable metadata (a name too long, a parent that is a file): the write will
        // report it; nothing has been opened.
        Err(_) => Ok(()),
    }
}

/// Check that `path` can hold the output files of `option`: an existing directory (also
/// through a link) or a name that does not exist yet (created with its parents).
pub fn check_directory(option: &'static str, path: &Path) -> Result<(), OutputError> {
    if path.as_os_str().is_empty() {
        return Err(unusable(option, path, "the name is empty"));
    }
    match std::fs::metadata(path) {
        Ok(metadata) if metadata.is_dir() => Ok(()),
        Ok(metadata) => Err(unusable(
            option,
            path,
            format!("it is {}, not a directory", file_kind(&metadata)),
        )),
        Err(_) => Ok(()),
    }
}

/// Create the directory `path` (and its parents) for the outputs of `option`.
pub fn create_directory(option: &'static str, path: &Path) -> Result<(), OutputError> {
    check_directory(option, path)?;
    std::fs::create_dir_all(path).map_err(|source| OutputError::Write {
        path: path.into(),
        source,
    })
}

/// Check that `path`'s name ends in one of `extensions` (without the dot), for an output
/// whose format is fixed by `option`: an SVG is never written to a `.png` name.
pub fn check_extension(
    option: &'static str,
    path: &Path,
    extensions: &[&str],
    format: &str,
) -> Result<(), OutputError> {
    let extension = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    if extensions
        .iter()
        .any(|allowed| extension.eq_ignore_ascii_case(allowed))
    {
        return Ok(());
    }
    let allowed: Vec<String> = extensions.iter().map(|e| format!(".{e}")).collect();
    Err(unusable(
        option,
        path,
        format!(
            "{option} writes {format}: give a name ending in {}",
            allowed.join(" or ")
        ),
    ))
}

/// Check that `path` is not a picture's name (`.svg`, `.png`), for an output of CSV text.
pub fn check_not_a_picture(option: &'static str, path: &Path) -> Result<(), OutputError> {
    match check_extension(option, path, &["svg", "png"], "") {
        Ok(()) => Err(unusable(
            option,
            path,
            format!("{option} writes CSV text, not a picture"),
        )),
        Err(_) => Ok(()),
    }
}

/// Where a path leads, to compare two outputs: the canonical directory and the file name
/// (the file need not exist), or the device and inode of an existing file.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
enum Identity {
    Name(PathBuf),
    #[cfg(unix)]
    Inode(u64, u64),
}

/// The identities of `path`: its canonical name, and its inode where it exists.
fn identities(path: &Path) -> Vec<Identity> {
    let mut found = Vec::new();
    let directory = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if let (Ok(directory), Some(name)) = (directory.canonicalize(), path.file_name()) {
        found.push(Identity::Name(directory.join(name)));
    } else {
        found.push(Identity::Name(path.to_path_buf()));
    }
    #[cfg(unix)]
    if let Ok(metadata) = std::fs::metadata(path) {
        use std::os::unix::fs::MetadataExt;
        found.push(Identity::Inode(metadata.dev(), metadata.ino()));
    }
    found
}

/// Check that no two of `outputs` (option, path) are the same file, and that none is one of
/// the `inputs` (the scene file): writing one would clobber the other.
pub fn check_distinct(
    outputs: &[(&'static str, &Path)],
    inputs: &[&Path],
) -> Result<(), OutputError> {
    let same = |a: &Path, b: &Path| {
        let theirs = identities(b);
        identities(a)
            .iter()
            .any(|identity| theirs.contains(identity))
    };
    for (i, (option, path)) in outputs.iter().enumerate() {
        if let Some(input) = inputs.iter().find(|input| same(path, input)) {
            let reason = format!(
                "it is the scene file '{}', which the run reads",
                input.display()
            );
            return Err(unusable(option, path, reason));
        }
        if let Some((other, _)) = outputs[..i].iter().find(|(_, other)| same(path, other)) {
            return Err(unusable(
                option,
                path,
                format!("{other} writes the same file"),
            ));
        }
    }
    Ok(())
}

/// The option names of a run's three outputs.
const TRAJECTORY: &str = "--out (output.trajectory)";
const PLOT: &str = "--plot (output.plot)";
/// The option name of the events' CSV file.
pub const EVENTS: &str = "--events-out (output.events)";

/// Check the outputs of a run before it starts: the trajectory and the events (CSV text, not
/// a picture's name) and the trajectory's plot (an `.svg` name) are files that can be
/// written, no two the same file, and none the scene file `source`.
pub fn check_run_outputs(
    trajectory: Option<&Path>,
    plot: Option<&Path>,
    events: Option<&Path>,
    source: Option<&Path>,
) -> Result<(), OutputError> {
    for (option, path) in [(TRAJECTORY, trajectory), (EVENTS, events)] {
        if let Some(path) = path {
            check_file(option, path)?;
            check_not_a_picture(option, path)?;
        }
    }
    if let Some(path) = plot {
        check_file(PLOT, path)?;
        check_extension(PLOT, path, &["svg"], "SVG")?;
    }
    let outputs: Vec<(&'static str, &Path)> =
        [(TRAJECTORY, trajectory), (PLOT, plot), (EVENTS, events)]
            .into_iter()
            .filter_map(|(option, path)| Some((option, path?)))
            .collect();
    check_distinct(&outputs, source.as_slice())
}

/// The temporaries not yet committed or removed, for [`remove_pending`].
static PENDING: Mutex<BTreeSet<PathBuf>> = Mutex::new(BTreeSet::new());

/// Remove every temporary not yet committed: for the binary's Ctrl-C and SIGTERM handler,
/// which then exits (destructors do not run on a signal's exit).
pub fn remove_pending() {
    let pending = match PENDING.lock() {
        Ok(pending) => pending,
        Err(poisoned) => poisoned.into_inner(),
    };
    for path in pending.iter() {
        let _ = std::fs::remove_file(path);
    }
}

/// A temporary's entry in the list [`remove_pending`] removes, dropped with it.
#[derive(Debug)]
struct Pending(PathBuf);

impl Pending {
    fn new(path: PathBuf) -> Pending {
        let mut pending = match PENDING.lock() {
            Ok(pending) => pending,
            Err(poisoned) => poisoned.into_inner(),
        };
        pending.insert(path.clone());
        Pending(path)
    }
}

impl Drop for Pending {
    fn drop(&mut self) {
        let mut pending = match PENDING.lock() {
            Ok(pending) => pending,
            Err(poisoned) => poisoned.into_inner(),
        };
        pending.remove(&self.0);
    }
}

/// An output file being written: a temporary beside the destination, renamed over it by
/// [`OutputFile::commit`] (see the module docs). Dropped uncommitted, the temporary is
/// removed and the destination is left as it was.
#[derive(Debug)]
pub struct OutputFile {
    destination: PathBuf,
    // Dropped in this order: the temporary is removed, then forgotten.
    out: BufWriter<tempfile::NamedTempFile>,
    _pending: Pending,
}

impl OutputFile {
    /// Check `path` ([`check_file`] for `option`) and create the temporary beside it, so that
    /// an unwritable destination is reported before any work.
    pub fn create(option: &'static str, path: &Path) -> Result<OutputFile, OutputError> {
        check_file(option, path)?;
        let directory = match path.parent() {
            Some(parent) if !parent.as_os_str().is_empty() => parent,
            _ => Path::new("."),
        };
        let mut builder = tempfile::Builder::new();
        builder.prefix(".svi-").suffix(".tmp");
        // The permissions of the file replaced (a private file stays private), else those of
        // a file made by `File::create` (0666 less the umask).
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let permissions = std::fs::symlink_metadata(path)
                .ok()
                .filter(Metadata::is_file)
                .map_or_else(
                    || std::fs::Permissions::from_mode(0o666),
                    |existing| existing.permissions(),
                );
            builder.permissions(permissions);
        }
        let file = builder
            .tempfile_in(directory)
            .map_err(|source| OutputError::Write {
                path: path.into(),
                source,
            })?;
        let pending = Pending::new(file.path().to_path_buf());
        Ok(OutputFile {
            destination: path.into(),
            out: BufWriter::new(file),
            _pending: pending,
        })
    }

    /// The destination.
    pub fn path(&self) -> &Path {
        &self.destination
    }

    /// Flush the bytes and rename the temporary over the destination.
    pub fn commit(self) -> Result<(), OutputError> {
        let OutputFile {
            destination, out, ..
        } = self;
        out.into_inner()
            .map_err(|error| error.into_error())
            .and_then(|file| file.persist(&destination).map_err(|error| error.error))
            .map(drop)
            .map_err(|source| OutputError::Write {
                path: destination.clone(),
                source,
            })
    }
}

impl Write for OutputFile {
    fn write(&mut self, bytes: &[u8]) -> io::Result<usize> {
        self.out.write(bytes)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }
}

/// The files a command writes into one directory (`--out-dir`), created as temporaries
/// before the work, so that an unwritable directory is reported before it, and put in place
/// together by [`OutputDirectory::commit`].
#[derive(Debug)]
pub struct OutputDirectory {
    directory: PathBuf,
    files: Vec<(String, OutputFile)>,
}

impl OutputDirectory {
    /// Create the directory `directory` of `option` (with its parents) and the temporaries
    /// of the files `names` in it; none of them may be one of `inputs` (the scene file).
    pub fn create(
        option: &'static str,
        directory: &Path,
        names: &[String],
        inputs: &[&Path],
    ) -> Result<OutputDirectory, OutputError> {
        create_directory(option, directory)?;
        let paths: Vec<PathBuf> = names.iter().map(|name| directory.join(name)).collect();
        let outputs: Vec<(&'static str, &Path)> =
            paths.iter().map(|path| (option, path.as_path())).collect();
        check_distinct(&outputs, inputs)?;
        let files = names
            .iter()
            .zip(&paths)
            .map(|(name, path)| Ok((name.clone(), OutputFile::create(option, path)?)))
            .collect::<Result<_, OutputError>>()?;
        Ok(OutputDirectory {
            directory: directory.into(),
            files,
        })
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.directory
    }

    /// Write `bytes` as the file `name` (one of those created).
    pub fn write(&mut self, name: &str, bytes: &[u8]) -> Result<(), OutputError> {
        let path = self.directory.join(name);
        let file = self
            .files
            .iter_mut()
            .find(|(file, _)| file == name)
            .map(|(_, file)| file)
            .ok_or_else(|| OutputError::Write {
                path: path.clone(),
                source: io::Error::other("not one of the files created for the directory"),
            })?;
        file.write_all(bytes)
            .map_err(|source| OutputError::Write { path, source })
    }

    /// Put every file in place.
    pub fn commit(self) -> Result<(), OutputError> {
        self.files
            .into_iter()
            .try_for_each(|(_, file)| file.commit())
    }
}

/// Write `bytes` to the output `path` of `option` atomically.
pub fn write_file(option: &'static str, path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let mut file = OutputFile::create(option, path)?;
    file.write_all(bytes).map_err(|source| OutputError::Write {
        path: path.into(),
        source,
    })?;
    file.commit()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A scratch directory of its own, removed at the end.
    fn scratch(name: &str) -> tempfile::TempDir {
        tempfile::Builder::new()
            .prefix(&format!("svi-output-{name}-"))
            .tempdir()
            .unwrap()
    }

    #[test]
    fn an_output_replaces_the_file_only_when_committed() {
        let dir = scratch("commit");
        let path = dir.path().join("out.csv");
        std::fs::write(&path, "old\n").unwrap();
        let mut file = OutputFile::create("--out", &path).unwrap();
        file.write_all(b"new\n").unwrap();
        file.flush().unwrap();
        // Not yet committed: the old file is whole, the temporary is hidden beside it.
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "old\n");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
        file.commit().unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "new\n");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        // Dropped uncommitted: the old file stays and the temporary is gone.
        let mut file = OutputFile::create("--out", &path).unwrap();
        file.write_all(b"torn").unwrap();
        drop(file);
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "new\n");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[cfg(unix)]
    #[test]
    fn a_replaced_file_keeps_its_permissions() {
        use std::os::unix::fs::PermissionsExt;
        let dir = scratch("mode");
        let path = dir.path().join("private.csv");
        std::fs::write(&path, "old\n").unwrap();
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o600)).unwrap();
        write_file("--out", &path, b"new\n").unwrap();
        let mode = std::fs::metadata(&path).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode, 0o600);
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "new\n");
    }

    #[cfg(unix)]
    #[test]
    fn a_planted_link_is_refused_and_never_followed() {
        let dir = scratch("link");
        let victim = dir.path().join("victim.txt");
        std::fs::write(&victim, "precious\n").unwrap();
        let link = dir.path().join("out.csv");
        std::os::unix::fs::symlink(&victim, &link).unwrap();
        let error = OutputFile::create("--out", &link).unwrap_err();
        assert!(error.is_bad_input());
        assert!(error.to_string().contains("symbolic link"), "{error}");
        // A link planted after the check is replaced by the rename, never written through.
        let other = dir.path().join("late.csv");
        let mut file = OutputFile::create("--out", &other).unwrap();
        std::os::unix::fs::symlink(&victim, &other).unwrap();
        file.write_all(b"output\n").unwrap();
        file.commit().unwrap();
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious\n");
        assert!(
            !std::fs::symlink_metadata(&other)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        assert_eq!(std::fs::read_to_string(&other).unwrap(), "output\n");
    }

    #[cfg(unix)]
    #[test]
    fn fifos_devices_and_directories_are_refused_before_they_are_opened() {
        let dir = scratch("kinds");
        let fifo = dir.path().join("fifo");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        let mut cases = vec![
            (PathBuf::from("/dev/null"), "character device"),
            (dir.path().to_path_buf(), "directory"),
            (PathBuf::from(""), "empty"),
            (PathBuf::from("-"), "not standard output"),
            (dir.path().join("sub/"), "names a directory"),
        ];
        if made.is_ok_and(|status| status.success()) {
            cases.push((fifo, "FIFO"));
        }
        for (path, what) in cases {
            let error = OutputFile::create("--out", &path).unwrap_err();
            assert!(error.is_bad_input(), "{path:?}");
            assert!(error.to_string().contains(what), "{path:?}: {error}");
        }
        let error = check_directory("--out-dir", Path::new("/dev/null")).unwrap_err();
        assert!(error.to_string().contains("not a directory"), "{error}");
        assert!(check_directory("--out-dir", dir.path()).is_ok());
    }

    #[test]
    fn two_outputs_of_one_file_or_an_output_over_the_scene_are_refused() {
        let dir = scratch("distinct");
        let scene = dir.path().join("scene.toml");
        std::fs::write(&scene, "model = \"kepler\"\n").unwrap();
        let csv = dir.path().join("out.csv");
        let same = dir.path().join(".").join("out.csv");
        let error = check_distinct(&[("--out", &csv), ("--plot", &same)], &[]).unwrap_err();
        assert!(
            error.to_string().contains("--out writes the same file"),
            "{error}"
        );
        let error = check_distinct(&[("--out", &scene)], &[&scene]).unwrap_err();
        assert!(error.to_string().contains("is the scene file"), "{error}");
        assert!(check_distinct(&[("--out", &csv)], &[&scene]).is_ok());
        // A hard link to the scene is the scene.
        let hard = dir.path().join("hard.csv");
        std::fs::hard_link(&scene, &hard).unwrap();
        assert!(check_distinct(&[("--out", &hard)], &[&scene]).is_err());
    }

    #[test]
    fn formats_follow_the_names() {
        assert!(check_extension("--plot", Path::new("a.svg"), &["svg"], "SVG").is_ok());
        assert!(check_extension("--plot", Path::new("a.SVG"), &["svg"], "SVG").is_ok());
        let error = check_extension("--plot", Path::new("a.png"), &["svg"], "SVG").unwrap_err();
        assert_eq!(
            error.to_string(),
            "cannot write --plot to 'a.png': --plot writes SVG: give a name ending in .svg"
        );
        assert!(check_not_a_picture("--out", Path::new("a.csv")).is_ok());
        assert!(check_not_a_picture("--out", Path::new("a.svg")).is_err());
    }
}
