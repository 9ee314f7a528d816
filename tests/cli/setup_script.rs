//! `.ci/setup-debian.sh` takes bookworm-backports from the mirror the machine
//! already uses for bookworm, not from a host name written into the script;
//! without one it fails and says what to configure.

use std::path::Path;
use std::process::Command;

/// `--print-mirror` with these files under a private APT_ETC: its exit
/// status, stdout and stderr.
fn print_mirror(files: &[(&str, &str)]) -> (bool, String, String) {
    let dir = std::env::temp_dir().join(format!("hybrid-rt-apt-{}-{}", std::process::id(), files.len()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("sources.list.d")).unwrap();
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap();
    }
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join(".ci/setup-debian.sh");
    let out = Command::new("bash").arg(script).arg("--print-mirror").env("APT_ETC", &dir).output().unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    let text = |b: Vec<u8>| String::from_utf8(b).unwrap().trim().to_string();
    (out.status.success(), text(out.stdout), text(out.stderr))
}

fn mirror_for(files: &[(&str, &str)]) -> String {
    let (ok, stdout, stderr) = print_mirror(files);
    assert!(ok, "{stderr}");
    stdout
}

#[test]
fn mirror_comes_from_deb822_sources() {
    let sources = "Types: deb\n# http://snapshot.debian.org/archive/debian/20250520T000000Z\n\
                   URIs: http://mirror.example.org/debian\nSuites: bookworm bookworm-updates\nComponents: main\n\n\
                   Types: deb\nURIs: http://security.example.org/debian-security\nSuites: bookworm-security\n";
    // A backports file sorting first must not be taken for the bookworm source.
    let backports = "Types: deb\nURIs: http://other.example.org/debian\nSuites: bookworm-backports\n";
    assert_eq!(
        mirror_for(&[
            ("sources.list.d/a-backports.sources", backports),
            ("sources.list.d/debian.sources", sources)
        ]),
        "http://mirror.example.org/debian"
    );
}

#[test]
fn mirror_comes_from_one_line_sources_list() {
    let list = "# deb http://commented.example.org/debian bookworm main\n\
                deb [arch=amd64 signed-by=/usr/share/keyrings/k.gpg] http://list.example.org/debian bookworm main\n";
    assert_eq!(mirror_for(&[("sources.list", list)]), "http://list.example.org/debian");
}

/// No bookworm source at all: the script names no host of its own, it
/// fails and says what to configure.
#[test]
fn no_bookworm_source_is_a_clear_error() {
    let other = "Types: deb\nURIs: http://other.example.org/debian\nSuites: trixie\n";
    for files in [&[][..], &[("sources.list.d/other.sources", other)][..]] {
        let (ok, stdout, stderr) = print_mirror(files);
        assert!(!ok, "succeeded with {stdout:?}");
        assert!(stdout.is_empty(), "{stdout}");
        assert!(stderr.contains("no bookworm") && stderr.contains("sources.list"), "{stderr}");
    }
    let script =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(".ci/setup-debian.sh")).unwrap();
    assert!(!script.contains("deb.debian.org"), "the script names a mirror host");
}
