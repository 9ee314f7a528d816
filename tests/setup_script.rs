//! `.ci/setup-debian.sh` takes bookworm-backports from the mirror the machine
//! already uses for bookworm, not from a host name written into the script.

use std::path::Path;
use std::process::Command;

fn mirror_for(files: &[(&str, &str)]) -> String {
    let dir = std::env::temp_dir().join(format!("hybrid-rt-apt-{}-{}", std::process::id(), files.len()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("sources.list.d")).unwrap();
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap();
    }
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join(".ci/setup-debian.sh");
    let out = Command::new("bash").arg(script).arg("--print-mirror").env("APT_ETC", &dir).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    std::fs::remove_dir_all(&dir).unwrap();
    String::from_utf8(out.stdout).unwrap().trim().to_string()
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

#[test]
fn mirror_falls_back_to_deb_debian_org() {
    assert_eq!(mirror_for(&[]), "http://deb.debian.org/debian");
}
