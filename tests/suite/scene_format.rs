//! docs/scene-format.md held to the parser, so the reference cannot go stale:
//!
//! - Each table after a `<!-- fields: SECTION -->` marker lists, in its first
//!   column, exactly the keys the parser accepts in that section. The parser
//!   is asked by giving it an unknown key there: every section refuses unknown
//!   fields, and serde's error lists the ones it expected.
//! - Each table after a `<!-- values: NAME -->` marker lists exactly the
//!   names the parser accepts for that string (asked with an unknown name).
//! - Each table after a `<!-- kinds: SECTION -->` marker lists a `type` per
//!   row and that type's fields in its second column: exactly the types the
//!   parser knows, each accepting its documented fields and refusing every
//!   other field of the section.
//! - Every ```json and ```toml block reads and resolves into a render job as
//!   `rtow render` would (the library's parser, then `Job::new`); a block
//!   marked `preset=NAME` is exactly the preset, and exactly the text `rtow
//!   export` writes for it. The examples cover the three books.
//!
//! A documented field the parser does not accept, or an accepted one the page
//! does not document, fails with its name (and a test below checks that the
//! checks do fail on a page changed that way).

use crate::common;
use rtow::scene::{self, Format};
use std::collections::BTreeSet;
use std::path::Path;

const DOC: &str = include_str!("../../docs/scene-format.md");
const DOC_NAME: &str = "docs/scene-format.md";

/// A minimal valid camera, the rest of a scene around the section tested.
const CAMERA: &str = r#""camera": {"look_from": [0, 0, 1], "look_at": [0, 0, 0]}"#;
const BOGUS: &str = "bogus_key";

/// A scene whose section `section` holds `inner` where a key or an object goes.
fn scene_around(section: &str, inner: &str) -> Option<String> {
    let body = match section {
        "scene" => return Some(format!("{{{inner}, {CAMERA}}}")),
        "camera" => return Some(format!("{{\"camera\": {{{inner}}}}}")),
        "sphere" => format!(r#""spheres": [{{{inner}}}]"#),
        "quad" => format!(r#""quads": [{{{inner}}}]"#),
        "box" => format!(r#""boxes": [{{{inner}}}]"#),
        "group" => format!(r#""groups": [{{{inner}}}]"#),
        "medium" => format!(r#""media": [{{{inner}}}]"#),
        "boundary" => format!(r#""media": [{{"boundary": {{{inner}}}}}]"#),
        "boundary.sphere" => format!(r#""media": [{{"boundary": {{"sphere": {{{inner}}}}}}}]"#),
        "boundary.box" => format!(r#""media": [{{"boundary": {{"box": {{{inner}}}}}}}]"#),
        "mesh" => format!(r#""meshes": [{{{inner}}}]"#),
        "mesh.icosphere" => format!(r#""meshes": [{{"shape": {{"icosphere": {{{inner}}}}}}}]"#),
        "mesh.obj" => format!(r#""meshes": [{{"shape": {{"obj": {{{inner}}}}}}}]"#),
        "material" => format!(r#""spheres": [{{"center": [0, 0, -2], "radius": 1, "material": {{{inner}}}}}]"#),
        "texture" => format!(
            r#""spheres": [{{"center": [0, 0, -2], "radius": 1, "material": {{"type": "lambertian", "albedo": {{{inner}}}}}}}]"#
        ),
        "shape" => format!(r#""sample_toward": [{{{inner}}}]"#),
        "sky" => format!(r#""sky": {{{inner}}}"#),
        "render" => format!(r#""render": {{{inner}}}"#),
        "render.book" => format!(r#""render": {{"book": {{{inner}}}}}"#),
        _ => return None,
    };
    Some(format!("{{{CAMERA}, {body}}}"))
}

/// The sections whose keys the page must list, and how each is asked.
const FIELD_SECTIONS: &[&str] = &[
    "scene",
    "camera",
    "sphere",
    "quad",
    "box",
    "group",
    "medium",
    "boundary",
    "boundary.sphere",
    "boundary.box",
    "mesh",
    "mesh.icosphere",
    "mesh.obj",
    "material",
    "texture",
    "sky",
    "render",
    "render.book",
];

/// The named values the page must list: a scene giving `bogus` for each.
fn scene_with_value(name: &str, bogus: &str) -> Option<String> {
    Some(match name {
        "mode" => format!(r#"{{"mode": "{bogus}", {CAMERA}}}"#),
        "sampler" => format!(r#"{{{CAMERA}, "render": {{"sampler": "{bogus}"}}}}"#),
        "estimator" => format!(r#"{{{CAMERA}, "render": {{"estimator": "{bogus}"}}}}"#),
        _ => return None,
    })
}
const VALUE_NAMES: &[&str] = &["mode", "sampler", "estimator"];
const KIND_SECTIONS: &[&str] = &["material", "texture", "shape"];

fn parse(json: &str) -> Result<scene::Scene, String> {
    scene::scene_from_str(json, Format::Json, Path::new("probe.json")).map_err(|e| e.to_string())
}

/// The names an error message lists after `after`: backticked (serde's
/// "`a`", "`a` or `b`", "one of `a`, `b`, ...") or comma-separated (rtow's
/// "'x' is not one of a, b, c").
fn listed(message: &str, after: &str) -> Option<BTreeSet<String>> {
    let start = message.find(after)? + after.len();
    let rest = &message[start..];
    let rest = rest.find(" (line ").map_or(rest, |i| &rest[..i]);
    if rest.contains('`') {
        Some(rest.split('`').skip(1).step_by(2).map(str::to_string).collect())
    } else {
        Some(rest.split(", ").map(|s| s.trim().to_string()).filter(|s| !s.is_empty()).collect())
    }
}

/// The keys the parser accepts in `section` (from its error on an unknown key).
fn accepted_keys(section: &str, problems: &mut Vec<String>) -> BTreeSet<String> {
    let json = scene_around(section, &format!(r#""{BOGUS}": 0"#)).expect("a known section");
    let message = match parse(&json) {
        Ok(_) => {
            problems.push(format!("section {section}: an unknown key was accepted"));
            return BTreeSet::new();
        }
        Err(e) => e,
    };
    listed(&message, &format!("unknown field `{BOGUS}`, expected ")).unwrap_or_else(|| {
        problems.push(format!("section {section}: the unknown key was not refused as one: {message}"));
        BTreeSet::new()
    })
}

/// Splits a table row into its cells (`\|` stays inside a cell).
fn cells(row: &str) -> Vec<String> {
    let mut out = vec![];
    let mut cell = String::new();
    let mut chars = row.trim().trim_start_matches('|').chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\\' if chars.peek() == Some(&'|') => {
                cell.push('|');
                chars.next();
            }
            '|' => out.push(std::mem::take(&mut cell).trim().to_string()),
            c => cell.push(c),
        }
    }
    if !cell.trim().is_empty() {
        out.push(cell.trim().to_string());
    }
    out
}

fn ticked(cell: &str) -> Vec<String> {
    cell.split('`').skip(1).step_by(2).map(str::to_string).collect()
}

/// The tables of a page after its `<!-- KIND: NAME -->` markers: each
/// NAME and its body rows' cells (the header and the rule skipped).
fn tables(doc: &str, kind: &str) -> Vec<(String, Vec<Vec<String>>)> {
    let marker = format!("<!-- {kind}: ");
    let lines: Vec<&str> = doc.lines().collect();
    let mut out = vec![];
    for (i, line) in lines.iter().enumerate() {
        if let Some(rest) = line.trim().strip_prefix(&marker) {
            let name = rest.trim_end_matches("-->").trim().to_string();
            let rows = lines[i + 1..]
                .iter()
                .skip_while(|l| l.trim().is_empty())
                .take_while(|l| l.trim_start().starts_with('|'))
                .skip(2)
                .map(|l| cells(l))
                .collect();
            out.push((name, rows));
        }
    }
    out
}

/// The first backticked name of each row's first cell.
fn first_names(rows: &[Vec<String>]) -> BTreeSet<String> {
    rows.iter().filter_map(|r| r.first().and_then(|c| ticked(c).into_iter().next())).collect()
}

fn compare(what: &str, documented: &BTreeSet<String>, accepted: &BTreeSet<String>, problems: &mut Vec<String>) {
    for name in documented.difference(accepted) {
        problems.push(format!("{what}: `{name}` is documented but the parser does not accept it"));
    }
    for name in accepted.difference(documented) {
        problems.push(format!("{what}: `{name}` is accepted by the parser but not documented"));
    }
}

/// A value for a field of a kinds section that every kind having it accepts.
fn sample_value(field: &str) -> &'static str {
    match field {
        "albedo" | "even" | "odd" | "emit" | "center" | "q" => "[0.5, 0.5, 0.5]",
        "u" => "[1, 0, 0]",
        "v" => "[0, 1, 0]",
        "fuzz" => "0.5",
        "ior" | "scale" | "radius" => "1.5",
        "one_sided" => "true",
        "file" => r#""map.png""#,
        other => panic!("{DOC_NAME}: no sample value for the field `{other}` in tests/suite/scene_format.rs; add one"),
    }
}

fn kind_object(kind: &str, fields: &BTreeSet<String>) -> String {
    let mut entries = vec![format!(r#""type": "{kind}""#)];
    entries.extend(fields.iter().map(|f| format!(r#""{f}": {}"#, sample_value(f))));
    entries.join(", ")
}

/// Every mismatch between `doc` and the parser, one line each.
fn problems_of(doc: &str) -> Vec<String> {
    let mut problems = vec![];

    let fields = tables(doc, "fields");
    for (name, _) in &fields {
        if !FIELD_SECTIONS.contains(&name.as_str()) {
            problems.push(format!("fields table `{name}`: not a section this test knows how to ask the parser about"));
        }
    }
    for section in FIELD_SECTIONS {
        match fields.iter().find(|(n, _)| n == section) {
            None => problems.push(format!("section {section}: no `<!-- fields: {section} -->` table")),
            Some((_, rows)) => {
                let accepted = accepted_keys(section, &mut problems);
                compare(&format!("section {section}"), &first_names(rows), &accepted, &mut problems);
            }
        }
    }

    let values = tables(doc, "values");
    for name in VALUE_NAMES {
        match values.iter().find(|(n, _)| n == name) {
            None => problems.push(format!("values of {name}: no `<!-- values: {name} -->` table")),
            Some((_, rows)) => {
                let json = scene_with_value(name, "bogus_value").expect("a known name");
                let accepted = match parse(&json) {
                    Ok(_) => BTreeSet::new(),
                    Err(e) => listed(&e, "expected ").or_else(|| listed(&e, "is not one of ")).unwrap_or_default(),
                };
                compare(&format!("values of {name}"), &first_names(rows), &accepted, &mut problems);
            }
        }
    }

    let kinds = tables(doc, "kinds");
    for section in KIND_SECTIONS {
        let Some((_, rows)) = kinds.iter().find(|(n, _)| n == section) else {
            problems.push(format!("kinds of {section}: no `<!-- kinds: {section} -->` table"));
            continue;
        };
        let documented: Vec<(String, BTreeSet<String>)> = rows
            .iter()
            .filter_map(|r| {
                let kind = ticked(r.first()?).into_iter().next()?;
                Some((kind, r.get(1).map(|c| ticked(c).into_iter().collect()).unwrap_or_default()))
            })
            .collect();
        // The types: exactly the parser's.
        let wrap = |inner: &str| scene_around(section, inner).expect("a known section");
        let known = match parse(&wrap(r#""type": "bogus_value""#)) {
            Ok(_) => BTreeSet::new(),
            Err(e) => listed(&e, "unknown variant `bogus_value`, expected ").unwrap_or_default(),
        };
        let names: BTreeSet<String> = documented.iter().map(|(k, _)| k.clone()).collect();
        compare(&format!("types of {section}"), &names, &known, &mut problems);
        // Every field the section has: the documented ones and any the parser lists.
        let mut all: BTreeSet<String> = documented.iter().flat_map(|(_, f)| f.iter().cloned()).collect();
        for (kind, _) in &documented {
            let message = parse(&wrap(&format!(r#""type": "{kind}", "{BOGUS}": 0"#))).err().unwrap_or_default();
            for f in listed(&message, &format!("unknown field `{BOGUS}`, expected ")).unwrap_or_default() {
                if f != "type" && !all.contains(&f) {
                    problems
                        .push(format!("{section} of type {kind}: `{f}` is accepted by the parser but not documented"));
                    all.insert(f);
                }
            }
        }
        for (kind, own) in &documented {
            if let Err(e) = parse(&wrap(&kind_object(kind, own))) {
                problems.push(format!("{section} of type {kind}: its documented fields are refused: {e}"));
            }
            for f in all.difference(own) {
                let mut with = own.clone();
                with.insert(f.clone());
                if parse(&wrap(&kind_object(kind, &with))).is_ok() {
                    problems.push(format!(
                        "{section} of type {kind}: `{f}` is accepted by the parser but not documented for this type"
                    ));
                }
            }
        }
    }
    problems
}

/// The fenced blocks of a page: their info string and their text.
fn blocks(doc: &str) -> Vec<(String, String)> {
    let mut out = vec![];
    let mut open: Option<(String, String)> = None;
    for line in doc.lines() {
        match (&mut open, line.trim_start().strip_prefix("```")) {
            (None, Some(info)) => open = Some((info.trim().to_string(), String::new())),
            (Some(_), Some(_)) => out.push(open.take().expect("an open block")),
            (Some((_, text)), None) => {
                text.push_str(line);
                text.push('\n');
            }
            (None, None) => {}
        }
    }
    out
}

#[test]
fn every_section_documents_exactly_the_fields_the_parser_accepts() {
    let problems = problems_of(DOC);
    assert!(problems.is_empty(), "{DOC_NAME} is not the parser's schema:\n{}", problems.join("\n"));
}

#[test]
fn the_checks_fail_on_a_field_documented_wrongly_or_not_at_all() {
    // `vup` left out of the camera's table, a `lens` the parser does not know
    // added to it, `fuzz` claimed for a dielectric, `one_sided` left out.
    let doc = DOC
        .replacen("| `vup` |", "| vup |", 1)
        .replacen("| `vfov_deg` |", "| `lens` | number | | | |\n| `vfov_deg` |", 1)
        .replacen("| `dielectric` | `ior` |", "| `dielectric` | `ior`, `fuzz` |", 1)
        .replacen("| `diffuse_light` | `emit`, `one_sided` |", "| `diffuse_light` | `emit` |", 1);
    let problems = problems_of(&doc).join("\n");
    for expected in [
        "section camera: `vup` is accepted by the parser but not documented",
        "section camera: `lens` is documented but the parser does not accept it",
        "material of type dielectric: its documented fields are refused",
        "material of type diffuse_light: `one_sided` is accepted by the parser but not documented for this type",
    ] {
        assert!(problems.contains(expected), "missing {expected:?} in:\n{problems}");
    }
}

#[test]
fn every_example_reads_and_resolves_and_the_preset_examples_are_what_export_writes() {
    let mut presets = vec![];
    let mut examples = 0;
    for (info, text) in blocks(DOC) {
        let mut words = info.split_whitespace();
        let format = match words.next() {
            Some("json") => Format::Json,
            Some("toml") => Format::Toml,
            _ => continue,
        };
        examples += 1;
        let scene = common::read_and_check(&text, format, DOC_NAME)
            .unwrap_or_else(|e| panic!("{DOC_NAME}: an example does not read or resolve: {e}\n{text}"));
        for name in words.filter_map(|w| w.strip_prefix("preset=")) {
            let preset = scene::preset(name).unwrap_or_else(|| panic!("{DOC_NAME}: no preset {name}"));
            let export = scene::scene_to_string(&preset, format);
            assert!(
                scene == preset && text.trim_end() == export.trim_end(),
                "{DOC_NAME}: the example marked preset={name} is not what `rtow export {name}` writes:\n{export}"
            );
            presets.push(name.to_string());
        }
    }
    assert!(examples >= 4, "{DOC_NAME}: {examples} examples");
    for (book, prefix) in
        [("Ray Tracing in One Weekend", "ch"), ("The Next Week", "nw-"), ("The Rest of Your Life", "rol-")]
    {
        assert!(
            presets.iter().any(|p| p.starts_with(prefix) || (prefix == "ch" && p == "final")),
            "{DOC_NAME}: no worked example of a preset of {book}"
        );
    }
}
