//! The buffers each pass declares (`Pass::reads`, `Pass::writes`) against the accesses its shader makes: the
//! barriers of a frame follow from the declarations alone (the validation layer cannot see accesses through
//! device addresses), so a missing one would be a silent race.
//!
//! The shader is read with the GLSL files it `#include`s; only functions reachable from `main` count. A buffer
//! is reached through its `FrameGlobals` address (`g.<field>`, `Resource::field`), directly or through a local
//! buffer reference (`CellRef cells = CellRef(g.hash_cells);`) or a parameter of a buffer reference type; or,
//! for the visibility, contact detail's buffer and the hash test cases, through a push-constant address
//! (`Resource::push_type`). An
//! access is a write when it is the target of an assignment (`=`, `+=`, `++`, …) or the first argument of an
//! atomic other than `atomicLoad`; read-modify-writes count as both.
use std::collections::{BTreeSet, HashMap, HashSet};
use std::path::{Path, PathBuf};

use hrtao_core::pass::{Pass, Resource};
use hrtao_core::passes::{self, pass_table_markdown};

fn shader_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shaders")
}

/// The text of `name` with its includes inlined once each, comments removed: a file of shaders/, or one build.rs
/// generates (the corrections' calls, corrections.glsl; gpu_types.glsl, which holds only types and constants, is
/// skipped).
fn source(name: &str, seen: &mut HashSet<String>) -> String {
    if !seen.insert(name.to_string()) || name == "gpu_types.glsl" {
        return String::new();
    }
    let path = shader_dir().join(name);
    let generated = Path::new(env!("OUT_DIR")).join(name);
    let Ok(text) = std::fs::read_to_string(&path).or_else(|_| std::fs::read_to_string(&generated)) else {
        panic!("{} not found, nor {}", path.display(), generated.display());
    };
    let mut out = String::new();
    for line in strip_comments(&text).lines() {
        let t = line.trim();
        if let Some(inc) = t.strip_prefix("#include") {
            out += &source(inc.trim().trim_matches('"'), seen);
        } else if !t.starts_with('#') {
            out += line;
            out.push('\n');
        }
    }
    out
}

fn strip_comments(s: &str) -> String {
    let mut out = String::new();
    let mut rest = s;
    while !rest.is_empty() {
        if let Some(r) = rest.strip_prefix("//") {
            rest = r.find('\n').map_or("", |i| &r[i..]);
        } else if let Some(r) = rest.strip_prefix("/*") {
            rest = r.find("*/").map_or("", |i| &r[i + 2..]);
        } else {
            let c = rest.chars().next().unwrap();
            out.push(c);
            rest = &rest[c.len_utf8()..];
        }
    }
    out
}

fn is_ident(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// Identifiers of `s` with their byte offsets.
fn idents(s: &str) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    let b = s.as_bytes();
    let mut i = 0;
    while i < b.len() {
        if is_ident(b[i] as char) && (i == 0 || !is_ident(b[i - 1] as char)) {
            let j = s[i..].find(|c: char| !is_ident(c)).map_or(s.len(), |k| i + k);
            out.push((i, &s[i..j]));
            i = j;
        } else {
            i += 1;
        }
    }
    out
}

/// A function definition: name, parameters, body.
struct Function {
    name: String,
    params: String,
    body: String,
}

/// The top-level function definitions of a source (brace matching).
fn functions(src: &str) -> Vec<Function> {
    let mut out = Vec::new();
    let b = src.as_bytes();
    let (mut depth, mut start) = (0usize, 0usize);
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'{' => {
                if depth == 0 {
                    let head = &src[start..i];
                    if let (Some(open), Some(close)) = (head.find('('), head.rfind(')')) {
                        let name = head[..open]
                            .trim_end()
                            .rsplit(|c: char| !is_ident(c))
                            .next()
                            .unwrap_or("")
                            .to_string();
                        let body_end = matching(src, i, b'{', b'}');
                        if !head.contains('=') && !head.trim_start().starts_with("layout") {
                            out.push(Function {
                                name,
                                params: head[open + 1..close].to_string(),
                                body: src[i + 1..body_end].to_string(),
                            });
                        }
                        i = body_end + 1;
                        start = i;
                        continue;
                    }
                }
                depth += 1;
            }
            b'}' => depth = depth.saturating_sub(1),
            b';' if depth == 0 => start = i + 1,
            _ => {}
        }
        if depth == 0 && b[i] == b'}' {
            start = i + 1;
        }
        i += 1;
    }
    out
}

/// The index of the bracket closing the one at `open`.
fn matching(s: &str, open: usize, o: u8, c: u8) -> usize {
    let b = s.as_bytes();
    let mut depth = 0;
    for (i, &ch) in b.iter().enumerate().skip(open) {
        if ch == o {
            depth += 1;
        } else if ch == c {
            depth -= 1;
            if depth == 0 {
                return i;
            }
        }
    }
    b.len() - 1
}

/// The buffer reference type names a source declares (`layout(buffer_reference, ...) buffer Name`).
fn reference_types(src: &str) -> HashSet<String> {
    let mut out = HashSet::new();
    for (i, _) in src.match_indices("buffer_reference") {
        let rest = &src[i..];
        if let Some(k) = rest.find(" buffer ") {
            let name: String = rest[k + 8..]
                .trim_start()
                .chars()
                .take_while(|&c| is_ident(c))
                .collect();
            out.insert(name);
        }
    }
    out
}

/// The resources the expression `e` names: `g.<field>` and push-constant reference types.
fn named(e: &str, aliases: &HashMap<String, BTreeSet<Resource>>) -> BTreeSet<Resource> {
    let mut out = BTreeSet::new();
    let ids = idents(e);
    for &(pos, id) in &ids {
        if pos >= 2 && &e[pos - 2..pos] == "g." {
            if let Some(r) = Resource::ALL.iter().find(|r| r.field() == Some(id)) {
                out.insert(*r);
            }
        } else if pos > 0 && e.as_bytes()[pos - 1] == b'.' {
            // A member.
        } else if let Some(r) = Resource::ALL.iter().find(|r| r.push_type() == Some(id)) {
            out.insert(*r);
        } else if let Some(rs) = aliases.get(id) {
            out.extend(rs.iter().copied());
        }
    }
    out
}

/// The accesses (resource, write) of one statement.
fn statement_accesses(
    st: &str,
    types: &HashSet<String>,
    aliases: &mut HashMap<String, BTreeSet<Resource>>,
    out: &mut BTreeSet<(Resource, bool)>,
) {
    let ids = idents(st);
    // A local buffer reference: `Type name = Type(...)` names the resources of its initialiser, no access.
    if let [(_, ty), (_, name), ..] = ids.as_slice() {
        let after = st[st.find(name).unwrap() + name.len()..].trim_start();
        if types.contains(*ty) && after.starts_with('=') && !after.starts_with("==") {
            let init = &after[1..];
            if init.trim_end().ends_with(')') {
                let rs = named(init, aliases);
                aliases.insert(name.to_string(), rs);
                return;
            }
        }
    }
    let b = st.as_bytes();
    // Writes: the target of an assignment (the postfix expression before the operator).
    let mut assigned = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        let is_assign = c == b'='
            && b.get(i + 1) != Some(&b'=')
            && (i == 0 || !matches!(b[i - 1], b'=' | b'!' | b'<' | b'>'));
        let incdec = (c == b'+' || c == b'-') && b.get(i + 1) == Some(&c);
        if is_assign || incdec {
            let compound =
                is_assign && i > 0 && matches!(b[i - 1], b'+' | b'-' | b'*' | b'/' | b'|' | b'&' | b'^');
            let end = if compound { i - 1 } else { i };
            let start = postfix_start(st, end);
            if start < end {
                assigned.push((start, end, compound || incdec));
            }
            if incdec {
                // `x++` or `++x`: the operand after as well.
                let after = i + 2;
                let stop = st[after..]
                    .find(|c: char| !(is_ident(c) || c == '.' || c == '[' || c == ']'))
                    .map_or(st.len(), |k| after + k);
                if stop > after {
                    assigned.push((after, stop, true));
                }
                i += 2;
                continue;
            }
        }
        i += 1;
    }
    let mut written_ranges = Vec::new();
    for &(s, e, rmw) in &assigned {
        for r in named(&st[s..e], aliases) {
            out.insert((r, true));
            if rmw {
                out.insert((r, false));
            }
        }
        written_ranges.push((s, e));
    }
    // Atomics: the first argument is read and written (atomicLoad: read, atomicStore: written).
    for &(pos, id) in &ids {
        if !id.starts_with("atomic") {
            continue;
        }
        let open = pos + id.len();
        if b.get(open) != Some(&b'(') {
            continue;
        }
        let close = matching(st, open, b'(', b')');
        let mut depth = 0;
        let mut first_end = close;
        for (k, &ch) in b.iter().enumerate().take(close).skip(open + 1) {
            match ch {
                b'(' | b'[' => depth += 1,
                b')' | b']' => depth -= 1,
                b',' if depth == 0 => {
                    first_end = k;
                    break;
                }
                _ => {}
            }
        }
        for r in named(&st[open + 1..first_end], aliases) {
            if id != "atomicStore" {
                out.insert((r, false));
            }
            if id != "atomicLoad" {
                out.insert((r, true));
            }
        }
        written_ranges.push((open + 1, first_end));
    }
    // Every other mention reads.
    let mut rest = String::with_capacity(st.len());
    for (k, ch) in st.char_indices() {
        let inside = written_ranges.iter().any(|&(s, e)| k >= s && k < e);
        rest.push(if inside { ' ' } else { ch });
    }
    for r in named(&rest, aliases) {
        out.insert((r, false));
    }
}

/// Where the postfix expression ending at `end` (exclusive, whitespace before it skipped) starts:
/// identifiers, members, indexing and calls (`Ref(g.x).v[i].field`).
fn postfix_start(s: &str, end: usize) -> usize {
    let b = s.as_bytes();
    let mut i = end;
    while i > 0 && b[i - 1].is_ascii_whitespace() {
        i -= 1;
    }
    loop {
        if i == 0 {
            return 0;
        }
        let c = b[i - 1];
        if c == b']' || c == b')' {
            let (o, cl) = if c == b']' { (b'[', b']') } else { (b'(', b')') };
            // Find the matching opening bracket backwards.
            let mut depth = 0;
            let mut j = i - 1;
            loop {
                if b[j] == cl {
                    depth += 1;
                } else if b[j] == o {
                    depth -= 1;
                    if depth == 0 {
                        break;
                    }
                }
                if j == 0 {
                    return i;
                }
                j -= 1;
            }
            if c == b')' && (j == 0 || !is_ident(b[j - 1] as char)) {
                // A parenthesised condition (`if (...) x = ...`): not part of the target.
                return i;
            }
            i = j;
        } else if is_ident(c as char) || c == b'.' {
            i -= 1;
        } else {
            return i;
        }
    }
}

/// The accesses of a pass's shader, from `main` and the functions it calls.
fn shader_accesses(pass: Pass) -> BTreeSet<(Resource, bool)> {
    let src = source(&format!("{}.comp", pass.shader()), &mut HashSet::new());
    let types = reference_types(&src);
    let funcs = functions(&src);
    // Reachable functions.
    let mut reach: Vec<&Function> = Vec::new();
    let mut names: Vec<String> = vec!["main".into()];
    let mut done = HashSet::new();
    while let Some(n) = names.pop() {
        if !done.insert(n.clone()) {
            continue;
        }
        for f in funcs.iter().filter(|f| f.name == n) {
            reach.push(f);
            for (_, id) in idents(&f.body) {
                if funcs.iter().any(|g| g.name == id) {
                    names.push(id.to_string());
                }
            }
        }
    }
    // What each buffer reference type is made from in the reachable code (for parameters of that type).
    let mut made_from: HashMap<String, BTreeSet<Resource>> = HashMap::new();
    for f in &reach {
        for (pos, id) in idents(&f.body) {
            if types.contains(id) && f.body.as_bytes().get(pos + id.len()) == Some(&b'(') {
                let close = matching(&f.body, pos + id.len(), b'(', b')');
                let rs = named(&f.body[pos + id.len()..=close], &HashMap::new());
                made_from.entry(id.to_string()).or_default().extend(rs);
            }
        }
    }
    let mut out = BTreeSet::new();
    for f in &reach {
        let mut aliases: HashMap<String, BTreeSet<Resource>> = HashMap::new();
        for p in f.params.split(',') {
            let ids = idents(p);
            if let [.., (_, ty), (_, name)] = ids.as_slice() {
                if types.contains(*ty) {
                    aliases.insert(name.to_string(), made_from.get(*ty).cloned().unwrap_or_default());
                }
            }
        }
        for st in f.body.split([';', '{', '}']) {
            statement_accesses(st, &types, &mut aliases, &mut out);
        }
    }
    out
}

/// The accesses a pass's shader makes that its declaration leaves out, as "Pass reads X" lines.
fn missing(pass: Pass) -> Vec<String> {
    shader_accesses(pass)
        .into_iter()
        .filter(|&(r, w)| !if w { pass.writes() } else { pass.reads() }.contains(&r))
        .map(|(r, w)| {
            format!(
                "{pass:?} ({}.comp) {} {r:?}",
                pass.shader(),
                if w { "writes" } else { "reads" }
            )
        })
        .collect()
}

#[test]
fn declarations_cover_every_shader_access() {
    let missing: Vec<String> = passes::ALL.iter().flat_map(|&p| missing(p)).collect();
    assert!(
        missing.is_empty(),
        "accesses the pass declarations (Pass::reads / Pass::writes) leave out:\n{}",
        missing.join("\n")
    );
}

/// Declared accesses the shader does not make cost barriers for nothing: each is listed.
#[test]
fn declarations_name_only_shader_accesses() {
    let mut extra = Vec::new();
    for pass in passes::ALL {
        let found = shader_accesses(pass);
        for &r in pass.reads() {
            if !found.contains(&(r, false)) {
                extra.push(format!("{pass:?} declares it reads {r:?}"));
            }
        }
        for &r in pass.writes() {
            if !found.contains(&(r, true)) {
                extra.push(format!("{pass:?} declares it writes {r:?}"));
            }
        }
    }
    assert!(
        extra.is_empty(),
        "declared but not in the shader:\n{}",
        extra.join("\n")
    );
}

/// The parser finds what it must on known statements (a parser that found nothing would pass the tests above).
#[test]
fn parser_finds_reads_writes_and_atomics() {
    let found = shader_accesses(Pass::PRIMARY);
    for a in [
        (Resource::DispatchArgs, true),
        (Resource::Stats, true),
        (Resource::GBuffer, true),
    ] {
        assert!(
            found.contains(&a),
            "primary.comp (with clear.glsl): {a:?} in {found:?}"
        );
    }
    // ray_target.glsl: `atomicAdd(StatsRef(g.stats).counters[STAT_RAY_QUEUE], 1u)` and the queue write.
    let found = shader_accesses(Pass::CELL_FINDER);
    for a in [
        (Resource::Stats, true),
        (Resource::Stats, false),
        (Resource::RayQueue, true),
    ] {
        assert!(found.contains(&a), "cell_finder.comp: {a:?} in {found:?}");
    }
}

/// The pass table in docs/architecture.md is the one the declarations give (between the marker comments).
#[test]
fn architecture_doc_has_the_pass_table() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/architecture.md");
    let doc = std::fs::read_to_string(&path).unwrap();
    let (begin, end) = ("<!-- pass-table:begin -->", "<!-- pass-table:end -->");
    let start = doc.find(begin).expect("begin marker") + begin.len();
    let stop = doc.find(end).expect("end marker");
    assert_eq!(doc[start..stop].trim(), pass_table_markdown().trim());
}

/// Prints the table (`cargo test -p hrtao-core --test pass_declarations print_pass_table -- --nocapture`).
#[test]
fn print_pass_table() {
    let table = pass_table_markdown();
    assert_eq!(table.lines().count(), passes::ALL.len() + 2);
    println!("{table}");
}
