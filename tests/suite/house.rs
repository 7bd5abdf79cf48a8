//! The house rules the compiler does not hold (docs/architecture.md, "Layers"): every import in
//! `src/` points down the layers, `vk/` has no import cycle, no pass imports another,
//! and nothing on the frame path uses a CPU reference. Read from the source text:
//! `crate::name` and `use crate::{...}` paths (`speculum::` in the binary), with
//! comments and `#[cfg(test)]` modules left out. Run alone: `cargo test --test suite house::`.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The layers, lowest first: a module may import only modules of a lower layer.
const LAYERS: &[&[&str]] = &[
    &["error", "shader_defines", "shaders"],
    &["gpu_types", "metrics", "output"],
    &["aabb", "vk"],
    &["settings", "scene"],
    &["sim"],
    &["tracers"],
    &["cpu_ref", "passes"],
    &["limits", "reflection_maps", "shadow_maps"],
    &["renderer"],
    &["report"],
    &["steady"],
    &["headless"],
    &["bench", "tune"],
    &["demo"],
    &["cli"],
];

/// The only modules that may use the CPU references (besides the tests): the frame
/// never does.
const CPU_REF_USERS: &[&str] = &["bench"];

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The code of a file without comments and without its `#[cfg(test)]` module.
fn code(path: &Path) -> String {
    let text = std::fs::read_to_string(path).unwrap();
    let text = text.split("#[cfg(test)]").next().unwrap();
    text.lines()
        .map(|l| match l.find("//") {
            // Not a `//` inside a string literal ("http://" and the like).
            Some(i) if l[..i].matches('"').count() % 2 == 0 => &l[..i],
            _ => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn ident(s: &str) -> &str {
    let end = s.find(|c: char| !(c.is_alphanumeric() || c == '_')).unwrap_or(s.len());
    &s[..end]
}

/// The first path segment after every `prefix::` in `code`, groups
/// (`prefix::{a, b::c}`) read to their first segments.
fn first_segments(code: &str, prefix: &str) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let pat = format!("{prefix}::");
    for (i, _) in code.match_indices(&pat) {
        // `crate::` only as a path's start (not `foo_crate::`).
        if code[..i].ends_with(|c: char| c.is_alphanumeric() || c == '_') {
            continue;
        }
        let rest = &code[i + pat.len()..];
        if let Some(group) = rest.strip_prefix('{') {
            let mut depth = 0;
            let mut item_start = true;
            for (k, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' if depth == 0 => break,
                    '}' => depth -= 1,
                    ',' if depth == 0 => item_start = true,
                    c if item_start && !c.is_whitespace() => {
                        item_start = false;
                        out.insert(ident(&group[k..]).to_string());
                    }
                    _ => {}
                }
            }
        } else {
            out.insert(ident(rest).to_string());
        }
    }
    out.remove("");
    out.remove("self");
    out
}

/// The top-level module a file of `src/` belongs to (`cli` for the binary's files).
fn module_of(rel: &Path) -> String {
    let first = rel.components().next().unwrap().as_os_str().to_str().unwrap();
    match first {
        "main.rs" | "cli" => "cli".into(),
        f => f.trim_end_matches(".rs").into(),
    }
}

/// Imports between top-level modules: (importer, imported) → a file that does it.
fn module_imports() -> BTreeMap<(String, String), String> {
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    let mut edges = BTreeMap::new();
    for f in files {
        let rel = f.strip_prefix(src()).unwrap().to_path_buf();
        if rel == Path::new("lib.rs") || rel == Path::new("shader_defines.rs") {
            continue;
        }
        let from = module_of(&rel);
        let code = code(&f);
        let names = first_segments(&code, "crate")
            .into_iter()
            .chain(first_segments(&code, "speculum"));
        for name in names {
            // Re-exports at the crate root (`crate::Result`, `speculum::Renderer`).
            let to = match name.as_str() {
                "Error" | "Result" => "error".to_string(),
                "Renderer" => "renderer".to_string(),
                "Settings" => "settings".to_string(),
                _ => name,
            };
            if to != from {
                edges.entry((from.clone(), to)).or_insert(rel.display().to_string());
            }
        }
    }
    edges
}

fn layer(module: &str) -> usize {
    LAYERS
        .iter()
        .position(|l| l.contains(&module))
        .unwrap_or_else(|| panic!("module {module} is in no layer of tests/suite/house.rs (add it)"))
}

#[test]
fn every_import_points_down_the_layers() {
    let edges = module_imports();
    assert!(edges.len() > 40, "the scan found only {} imports", edges.len());
    let wrong: Vec<String> = edges
        .iter()
        .filter(|((from, to), _)| layer(to) >= layer(from))
        .map(|((from, to), file)| format!("{from} -> {to} (src/{file})"))
        .collect();
    assert!(
        wrong.is_empty(),
        "imports that do not point down:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn only_benchmarks_use_the_cpu_references() {
    let wrong: Vec<String> = module_imports()
        .iter()
        .filter(|((from, to), _)| to == "cpu_ref" && !CPU_REF_USERS.contains(&from.as_str()))
        .map(|((from, _), file)| format!("{from} (src/{file})"))
        .collect();
    assert!(wrong.is_empty(), "CPU references used by:\n{}", wrong.join("\n"));
}

/// Imports among the submodules of the folder `dir` (via `super::` and `crate::<top>::`):
/// file stem → siblings it names.
fn sibling_imports(dir: &str, top: &str) -> BTreeMap<String, BTreeSet<String>> {
    let path = src().join(dir);
    let mut files = Vec::new();
    rust_files(&path, &mut files);
    let stem = |p: &Path| {
        let rel = p.strip_prefix(&path).unwrap();
        let first = rel.components().next().unwrap().as_os_str().to_str().unwrap();
        first.trim_end_matches(".rs").to_string()
    };
    let siblings: BTreeSet<String> = files.iter().map(|f| stem(f)).filter(|s| s != "mod").collect();
    let mut out = BTreeMap::new();
    for f in &files {
        let me = stem(f);
        if me == "mod" {
            continue;
        }
        let code = code(f);
        let mut named: BTreeSet<String> = first_segments(&code, &format!("crate::{top}"));
        // `super::x` from a file directly in the folder names a sibling (or an item of
        // mod.rs, which is not a sibling).
        if f.parent() == Some(path.as_path()) {
            named.extend(first_segments(&code, "super"));
        }
        let named: BTreeSet<String> = named.into_iter().filter(|n| siblings.contains(n) && *n != me).collect();
        out.insert(me, named);
    }
    out
}

/// A cycle among the siblings of `graph` (file stem → siblings it imports), as the
/// path that closes it, by depth-first search for a back edge.
fn import_cycle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        n: &str,
        g: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        path: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        match state.get(n) {
            Some(1) => {
                let start = path.iter().position(|p| p == n).unwrap();
                let mut cycle = path[start..].to_vec();
                cycle.push(n.to_string());
                return Some(cycle);
            }
            Some(_) => return None,
            None => {}
        }
        state.insert(n.to_string(), 1);
        path.push(n.to_string());
        for m in g.get(n).into_iter().flatten() {
            if let Some(c) = visit(m, g, state, path) {
                return Some(c);
            }
        }
        path.pop();
        state.insert(n.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    graph.keys().find_map(|n| visit(n, graph, &mut state, &mut Vec::new()))
}

#[test]
fn vk_has_no_import_cycle() {
    let graph = sibling_imports("vk", "vk");
    assert!(graph.len() >= 8, "vk/ has {} files", graph.len());
    assert!(
        graph.values().any(|n| !n.is_empty()),
        "the scan found no imports in vk/"
    );
    if let Some(cycle) = import_cycle(&graph) {
        panic!("vk/ import cycle: {}", cycle.join(" -> "));
    }
}

/// No folder of `src/` has an import circle among its files (`bench/embree.rs` and
/// `bench/lbvh.rs` had one: both now import `bench/anchor.rs`).
#[test]
fn no_folder_has_an_import_cycle() {
    let folders = [
        "bench",
        "cpu_ref",
        "demo",
        "tracers",
        "tracers/lbvh",
        "renderer",
        "scene",
        "settings",
        "sim",
        "tune",
        "vk",
    ];
    let mut scanned = 0;
    for dir in folders {
        let top = dir.replace('/', "::");
        let graph = sibling_imports(dir, &top);
        scanned += graph.values().filter(|n| !n.is_empty()).count();
        if let Some(cycle) = import_cycle(&graph) {
            panic!("{dir}/ import cycle: {}", cycle.join(" -> "));
        }
    }
    assert!(scanned >= 10, "the scan found imports in only {scanned} files");
    // The search itself finds a planted circle.
    let planted: BTreeMap<String, BTreeSet<String>> = [("a", "b"), ("b", "c"), ("c", "a")]
        .into_iter()
        .map(|(f, t)| (f.to_string(), BTreeSet::from([t.to_string()])))
        .collect();
    assert_eq!(
        import_cycle(&planted),
        Some(vec!["a".into(), "b".into(), "c".into(), "a".into()])
    );
}

#[test]
fn no_pass_imports_another() {
    let graph = sibling_imports("passes", "passes");
    assert!(graph.len() >= 12, "passes/ has {} files", graph.len());
    let wrong: Vec<String> = graph
        .iter()
        .filter(|(_, named)| !named.is_empty())
        .map(|(pass, named)| format!("{pass} -> {named:?}"))
        .collect();
    assert!(
        wrong.is_empty(),
        "passes that import other passes:\n{}",
        wrong.join("\n")
    );
}

/// The scanner itself: groups, nesting, and what is not a path start.
#[test]
fn the_scanner_reads_paths_and_groups() {
    let code = "use crate::{a::b, c, d::{e, f}};\nlet x = crate::g::h(); my_crate::z; crate::{ i };";
    let got: Vec<String> = first_segments(code, "crate").into_iter().collect();
    assert_eq!(got, ["a", "c", "d", "g", "i"]);
}

/// Roots of absolute paths where data lives only on the machine that wrote it: a test
/// or the program reading a model, image or scene there passes only on that machine.
/// (Named without the leading slash, so this file does not plant them.)
const MACHINE_DATA_ROOTS: &[&str] = &["tmp", "root", "home", "mnt", "media", "srv", "opt", "data", "Users"];

/// Absolute paths under those roots that are the system's, not data: the X server's
/// sockets and lock files (the window tests look for a display).
const SYSTEM_PATHS: &[&str] = &["tmp/.X11-unix/", "tmp/.X"];

/// The string literals of `text` that name a path under `MACHINE_DATA_ROOTS`
/// (a model under the machine's temporary folder, a home folder), with their line
/// numbers; comments left out.
fn machine_data_paths(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let code = match line.find("//") {
            Some(i) if line[..i].matches('"').count() % 2 == 0 => &line[..i],
            _ => line,
        };
        // Every other quote opens a literal (escaped quotes are rare in paths).
        for lit in code.split('"').skip(1).step_by(2) {
            let Some(path) = lit.strip_prefix('/') else { continue };
            let under_root = MACHINE_DATA_ROOTS.iter().any(|root| {
                path.strip_prefix(root)
                    .is_some_and(|rest| rest.is_empty() || rest.starts_with('/'))
            });
            if under_root && !SYSTEM_PATHS.iter().any(|s| path.starts_with(s)) {
                out.push((n + 1, lit.to_string()));
            }
        }
    }
    out
}

/// A fresh clone's `tools/test` must pass on a machine that never saw the repository:
/// no file of `src/`, `tests/`, `examples/` or `build.rs` names data by an absolute
/// path outside the repository. Tests read `tests/data`, `assets`, what they generate,
/// or a temporary directory they made; outside models are benchmark arguments.
#[test]
fn nothing_reads_data_from_outside_the_repository() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = vec![root.join("build.rs")];
    for dir in ["src", "tests", "examples"] {
        rust_files(&root.join(dir), &mut files);
    }
    assert!(files.len() > 100, "the scan found only {} files", files.len());
    let wrong: Vec<String> = files
        .iter()
        .flat_map(|f| {
            let rel = f.strip_prefix(root).unwrap().display().to_string();
            machine_data_paths(&std::fs::read_to_string(f).unwrap())
                .into_iter()
                .map(move |(line, lit)| format!("{rel}:{line}: \"{lit}\""))
        })
        .collect();
    assert!(
        wrong.is_empty(),
        "absolute paths to data outside the repository (use tests/data, assets, a tempdir, or a benchmark argument):\n{}",
        wrong.join("\n")
    );
}

/// The path scan itself: it flags the probe that broke a fresh clone's tests (its load
/// line, planted here), and passes repository paths, the X server's files and comments.
#[test]
fn the_path_scan_flags_machine_data_and_passes_system_paths() {
    // Built with format! so this file does not plant the paths it tests.
    let tmp = format!("/{}", "tmp");
    let probe = format!("    for name in [\"spheres\", \"gallery\", \"{tmp}/models/bunny.obj\"] {{");
    assert_eq!(machine_data_paths(&probe), [(1, format!("{tmp}/models/bunny.obj"))]);
    let home = format!(
        "let m = load(\"/{}/me/sponza.obj\")?;\nlet r = Path::new(\"/{}\");",
        "home", "root"
    );
    assert_eq!(
        machine_data_paths(&home),
        [(1, format!("/{}/me/sponza.obj", "home")), (2, format!("/{}", "root"))]
    );
    let fine = format!(
        "let s = \"assets/room.toml\"; Path::new(\"{tmp}/.X11-unix/X{{n}}\"); \"{tmp}/.X{{n}}-lock\";\n\
         // a comment naming {tmp}/models is no read\nlet d = \"/dev/null\"; let t = \"{tmp}x\";"
    );
    assert_eq!(machine_data_paths(&fine), []);
}

/// Lines a function of `src/` may have, its signature and closing brace included,
/// unless a `// Long:` comment right above it (among its docs and attributes) says why.
const FN_LINES_MAX: usize = 100;

/// Every function of a Rust source text at the top level or in an `impl`/`mod` (as
/// rustfmt writes them: the closing brace at the `fn`'s indentation): (name, first
/// line, lines, whether a `// Long:` comment stands in the lines just above it).
fn functions(text: &str) -> Vec<(String, usize, usize, bool)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = Vec::new();
    for (i, line) in lines.iter().enumerate() {
        let trimmed = line.trim_start();
        let indent = &line[..line.len() - trimmed.len()];
        let rest = ["pub(crate) ", "pub(super) ", "pub ", "const ", "async ", "unsafe "]
            .iter()
            .fold(trimmed, |t, p| t.strip_prefix(p).unwrap_or(t));
        let Some(sig) = rest.strip_prefix("fn ") else { continue };
        let name = ident(sig).to_string();
        // The body opens where the signature ends with `{` (a `;` is a declaration).
        let Some(open) = lines[i..].iter().position(|l| l.ends_with('{') || l.ends_with(';')) else {
            continue;
        };
        if lines[i + open].ends_with(';') || lines[i + open].trim_end().ends_with('}') {
            continue;
        }
        let close = format!("{indent}}}");
        let Some(end) = lines[i + open..].iter().position(|l| *l == close) else {
            continue;
        };
        let mut above = i;
        let mut reason = false;
        while above > 0 {
            let l = lines[above - 1].trim_start();
            if !(l.starts_with("//") || l.starts_with("#[")) {
                break;
            }
            reason |= l.starts_with("// Long:");
            above -= 1;
        }
        out.push((name, i + 1, open + end + 1, reason));
    }
    out
}

/// No function of `src/` runs past `FN_LINES_MAX` lines without its reason in the code
/// (the frame function is docs/architecture.md's frame table; a CPU reference may mirror its
/// kernel's one function).
#[test]
fn functions_stay_short_or_say_why() {
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    let mut long = Vec::new();
    let mut count = 0;
    for f in &files {
        let rel = f.strip_prefix(src()).unwrap().display().to_string();
        let text = std::fs::read_to_string(f).unwrap();
        let text = text.split("#[cfg(test)]").next().unwrap();
        for (name, line, len, reason) in functions(text) {
            count += 1;
            if len > FN_LINES_MAX && !reason {
                long.push(format!("src/{rel}::{name} (line {line}): {len} lines"));
            }
        }
    }
    assert!(count > 500, "the scan found only {count} functions");
    assert!(
        long.is_empty(),
        "functions over {FN_LINES_MAX} lines: split them, or say why in a `// Long:` comment above:\n{}",
        long.join("\n")
    );
}

/// The function scan itself: a long function, a declaration, a one-liner, a reason.
#[test]
fn the_function_scan_measures_bodies_and_reads_reasons() {
    let body = "    let x = 1;\n".repeat(3);
    let text = format!(
        "fn a() {{\n{body}}}\n\nimpl T {{\n    /// Docs.\n    // Long: a reason.\n    #[inline]\n    pub fn b(\n        x: u32,\n    ) -> u32 {{\n{body}    }}\n    fn c();\n    fn d() {{}}\n}}\n"
    );
    let got: Vec<(String, usize, usize, bool)> = functions(&text);
    assert_eq!(got, [("a".into(), 1, 5, false), ("b".into(), 11, 7, true)]);
}

/// Lines a file of `src/` may have before its tests module.
const FILE_LINES_MAX: usize = 600;

/// No file of `src/` grows past `FILE_LINES_MAX` lines of code (its `#[cfg(test)]`
/// module aside).
#[test]
fn files_stay_readable() {
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    let mut long = Vec::new();
    for f in &files {
        let rel = f.strip_prefix(src()).unwrap().display().to_string();
        let text = std::fs::read_to_string(f).unwrap();
        let lines = text.split("#[cfg(test)]").next().unwrap().lines().count();
        if lines > FILE_LINES_MAX {
            long.push(format!("src/{rel}: {lines} lines"));
        }
    }
    assert!(
        long.is_empty(),
        "files over {FILE_LINES_MAX} lines:\n{}",
        long.join("\n")
    );
}

/// Every `unsafe` block and impl outside `src/vk/` says why it is sound: clippy's
/// `undocumented_unsafe_blocks` is denied for the whole package (Cargo.toml's
/// `[lints.clippy]`, which CI's clippy run applies), and only `src/vk/mod.rs`, the thin
/// layer of Vulkan calls, allows it.
#[test]
fn unsafe_outside_vk_says_why() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let manifest = std::fs::read_to_string(root.join("Cargo.toml")).unwrap();
    let lints = manifest
        .split("[lints.clippy]")
        .nth(1)
        .expect("Cargo.toml has [lints.clippy]");
    assert!(
        lints
            .lines()
            .any(|l| l.replace(' ', "") == "undocumented_unsafe_blocks=\"deny\""),
        "Cargo.toml's [lints.clippy] denies undocumented_unsafe_blocks"
    );
    let mut files = Vec::new();
    rust_files(&src(), &mut files);
    rust_files(&root.join("tests"), &mut files);
    // (Split, so this file does not name itself.)
    let needle = ["allow(clippy::", "undocumented_unsafe_blocks)"].concat();
    let allowed: Vec<String> = files
        .iter()
        .filter(|f| std::fs::read_to_string(f).unwrap().contains(&needle))
        .map(|f| f.strip_prefix(root).unwrap().display().to_string())
        .collect();
    assert_eq!(
        allowed,
        ["src/vk/mod.rs"],
        "only vk/ may leave unsafe blocks unexplained"
    );
}

/// The settings' words the frame's decisions are made of: only the plan reads them.
const DECISIONS: &[&str] = &[
    ".mode",
    "Mode::",
    "hybrid_policy",
    "HybridPolicy",
    "exchange_rate",
    "st.glossy",
    ".uses_map()",
    ".traces()",
    ".marches()",
    ".reflects()",
    ".has_seams()",
];

fn decisions_in(code: &str) -> Vec<&'static str> {
    DECISIONS.iter().copied().filter(|w| code.contains(w)).collect()
}

/// `record_frame` reads the frame plan as a table: frame.rs decides nothing from the
/// settings or the mode (renderer/plan.rs does, unit-tested), and holds no function
/// long enough to need a `// Long:` exemption.
#[test]
fn the_frame_reads_its_plan() {
    let path = src().join("renderer/frame.rs");
    assert_eq!(
        decisions_in(&code(&path)),
        Vec::<&str>::new(),
        "decided in frame.rs, not in the plan"
    );
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(!text.contains("// Long:"), "frame.rs needs no long function");
    // The scan sees a decision where one is made.
    let made = "let adaptive = st.mode.marches() && st.hybrid_policy == HybridPolicy::Adaptive;";
    assert_eq!(
        decisions_in(made),
        [".mode", "hybrid_policy", "HybridPolicy", ".marches()"]
    );
}

/// What a frame's tracer is, is decided once: `renderer/tracer.rs` turns the setting into
/// one value of one tracer's kernels and structures (`FrameTracer`), and the tracers'
/// types do the rest (`tracers::Tracer`). No pass, no other renderer file and no tracer
/// compares or matches the setting.
#[test]
fn the_tracer_is_chosen_once() {
    const CHOICES: &[&str] = &[
        "Tracer::Khr",
        "Tracer::Lbvh",
        ".tracer ==",
        ".tracer !=",
        "match settings.tracer",
        "st.tracer",
    ];
    let allowed = ["renderer/tracer.rs", "tracers/mod.rs"];
    let mut files = Vec::new();
    for dir in ["passes", "renderer", "tracers"] {
        rust_files(&src().join(dir), &mut files);
    }
    assert!(files.len() > 20, "the scan found only {} files", files.len());
    let wrong: Vec<String> = files
        .iter()
        .filter(|f| !allowed.iter().any(|a| f.ends_with(a)))
        .flat_map(|f| {
            let code = code(f);
            let rel = f.strip_prefix(src()).unwrap().display().to_string();
            CHOICES
                .iter()
                .filter(move |c| chooses(&code, c))
                .map(move |c| format!("src/{rel}: {c}"))
        })
        .collect();
    assert!(wrong.is_empty(), "the tracer chosen again:\n{}", wrong.join("\n"));
    // The scan sees a choice where one is made (the old frame's), not in a name that
    // ends like one (`FrameTracer::Khr`).
    let old = "if settings.tracer != Tracer::Khr { return Ok(None); }";
    assert!(CHOICES.iter().any(|c| chooses(old, c)));
    assert!(!chooses("FrameTracer::Khr(kernels, khr) => {", "Tracer::Khr"));
}

/// Whether `code` holds `choice` other than as the end of a longer name.
fn chooses(code: &str, choice: &str) -> bool {
    code.match_indices(choice).any(|(i, _)| {
        let before = code[..i].chars().next_back();
        !before.is_some_and(|c| c.is_alphanumeric() || c == '_')
    })
}

/// Every screen pass is resized with the screen, in one place: each field of
/// `renderer/passes.rs`'s groups whose type has a `resize` (a pass of `src/passes/` with
/// screen-sized outputs) is resized by its group's `resize`, and the renderer resizes the
/// groups, not their passes.
#[test]
fn every_screen_pass_is_resized_by_its_group() {
    // The pass types with a `resize`: the `impl` that holds it.
    let mut files = Vec::new();
    rust_files(&src().join("passes"), &mut files);
    let mut resized_types = BTreeSet::new();
    for f in &files {
        let code = code(f);
        let Some(at) = code.find("pub fn resize(") else {
            continue;
        };
        let before = &code[..at];
        let imp = before.rfind("\nimpl ").expect("resize inside an impl");
        resized_types.insert(ident(before[imp + 6..].trim_start()).to_string());
    }
    assert!(resized_types.len() >= 10, "found {resized_types:?}");
    let groups = code(&src().join("renderer/passes.rs"));
    let mut fields = 0;
    for line in groups.lines() {
        let Some((name, ty)) = line.trim().strip_prefix("pub ").and_then(|l| l.split_once(": ")) else {
            continue;
        };
        let ty = ty.trim_end_matches(',');
        if resized_types.contains(ty) {
            fields += 1;
            assert!(
                groups.contains(&format!("self.{name}.resize(extent)")),
                "renderer/passes.rs: `{name}: {ty}` is screen-sized but its group's resize leaves it"
            );
        }
    }
    assert!(fields >= 9, "the scan found {fields} screen-sized fields in the groups");
    let renderer = code(&src().join("renderer/mod.rs"));
    let resizes = renderer.matches(".resize(").count();
    assert_eq!(
        resizes, 3,
        "renderer/mod.rs resizes the two groups and compose, nothing else"
    );
}
