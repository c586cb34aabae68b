//! The facade's shape: a small root (the `Field` value, the error, the options and result
//! types, modules by job), and no library message naming a command-line flag, since Python
//! users see the library's messages too.

use std::path::Path;

/// The names `lib.rs` puts at the crate root: items it defines and names it re-exports,
/// leaving out modules and re-exported crates (`pub use pgvol_x as y;`, `pub use glam;`).
fn root_items(lib: &str) -> Vec<String> {
    let mut names = Vec::new();
    let mut statement = String::new();
    let mut depth = 0usize;
    for line in lib.lines() {
        let trimmed = line.trim();
        // A use statement's braces are its list, not a block: they are not counted.
        let in_use =
            !statement.is_empty() || trimmed.starts_with("pub use ") || trimmed.starts_with("use ");
        if in_use {
            statement.push_str(trimmed);
            statement.push(' ');
            if trimmed.ends_with(';') {
                // Only top-level statements: the bodies of inline modules are skipped.
                if depth == 0 && statement.starts_with("pub use ") {
                    names.extend(used_names(&statement));
                }
                statement.clear();
            }
            continue;
        }
        if depth == 0 {
            if let Some(rest) = [
                "pub fn ",
                "pub struct ",
                "pub enum ",
                "pub const ",
                "pub type ",
            ]
            .iter()
            .find_map(|p| trimmed.strip_prefix(p))
            {
                let name: String = rest
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                names.push(name);
            }
        }
        if !trimmed.starts_with("//") {
            depth += line.matches('{').count();
            depth = depth.saturating_sub(line.matches('}').count());
        }
    }
    names
}

/// The names one `pub use …;` statement brings in; none for a crate re-export.
fn used_names(statement: &str) -> Vec<String> {
    let body = statement
        .trim()
        .trim_start_matches("pub use ")
        .trim_end_matches(';')
        .trim();
    if !body.contains("::") || body.contains(" as ") && !body.contains('{') {
        return Vec::new();
    }
    let list = match (body.find('{'), body.rfind('}')) {
        (Some(a), Some(b)) => &body[a + 1..b],
        _ => body.rsplit("::").next().unwrap_or(""),
    };
    list.split(',')
        .map(|n| n.trim().rsplit(' ').next().unwrap_or("").to_string())
        .filter(|n| !n.is_empty())
        .collect()
}

fn source(path: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(path);
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[test]
fn the_root_holds_at_most_sixty_items() {
    let names = root_items(&source("src/lib.rs"));
    // What must be there, so an empty count cannot pass.
    for name in [
        "Field",
        "Error",
        "EncodeOptions",
        "DecodeOptions",
        "SliceOptions",
        "Result",
    ] {
        assert!(
            names.iter().any(|n| n == name),
            "{name} missing from {names:?}"
        );
    }
    assert!(names.len() <= 60, "{} root items: {names:?}", names.len());
}

#[test]
fn no_library_string_names_a_command_line_flag() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = vec![dir.clone()];
    let mut offenders = Vec::new();
    let mut read = 0;
    while let Some(path) = files.pop() {
        if path.is_dir() {
            files.extend(std::fs::read_dir(&path).unwrap().map(|e| e.unwrap().path()));
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        read += 1;
        for (n, line) in text.lines().enumerate() {
            let code = line.trim_start();
            if code.starts_with("//") {
                continue;
            }
            // A flag inside a string literal: `"… --name …"`.
            let mut in_string = false;
            let bytes: Vec<char> = code.chars().collect();
            for i in 0..bytes.len() {
                if bytes[i] == '"' && (i == 0 || bytes[i - 1] != '\\') {
                    in_string = !in_string;
                }
                if in_string
                    && bytes[i..].starts_with(&['-', '-'])
                    && bytes.get(i + 2).is_some_and(|c| c.is_ascii_lowercase())
                {
                    offenders.push(format!("{}:{}: {}", path.display(), n + 1, line.trim()));
                    break;
                }
            }
        }
    }
    assert!(read > 20, "only {read} source files found");
    assert!(offenders.is_empty(), "{offenders:#?}");
}

#[test]
fn the_counters_see_what_they_look_for() {
    let lib = "pub use a::{B, C as D};\npub use pgvol_x as x;\npub mod m {\n    pub use q::R;\n}\npub fn e() {}\n";
    assert_eq!(root_items(lib), ["B", "D", "e"]);
}
