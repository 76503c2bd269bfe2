//! Wavefront OBJ files: read into a [`TriMesh`] (parsed by tobj) and
//! written from meshes.
//!
//! # Reading
//!
//! [`read_obj`] reads the regular file at a path; before it reads anything
//! it refuses a path that is something else (a folder, a FIFO, a socket, a
//! device, a link to nothing) and a file larger than
//! [`MAX_MESH_FILE_BYTES`]. [`parse_obj`] reads a file's bytes.
//!
//! What is read: positions (`v x y z`, with an optional fourth number `w`
//! that divides them, or an `r g b` colour, which is dropped), normals
//! (`vn`), and faces (`f`, each vertex `v`, `v/vt`, `v//vn` or `v/vt/vn`;
//! a negative index counts back from the last element defined before the
//! face line), polygons split into fans from their first vertex
//! (`f a b c d` gives `a b c` and `a c d`). Texture coordinates (`vt`) are
//! checked and dropped. Materials (`mtllib`, `usemtl`) are not loaded: no
//! `.mtl` file is opened. The objects and groups of a file (`o`, `g`) are
//! merged into one mesh, in file order. Other statements (`s`, `p`, curves
//! and surfaces) are ignored. A UTF-8 byte-order mark is skipped.
//!
//! The mesh's vertices are the corners of its faces: within an object, one
//! per distinct combination of position, texture coordinate and normal
//! indices (tobj's single index, so each vertex has its own normal),
//! numbered in the order the faces first use them. A position no face uses
//! is dropped, and a position met with two different normals becomes two
//! vertices. Normals are kept only if every vertex has one; otherwise the
//! mesh has none.
//!
//! Refused (exit status 2), with a message naming the file and, for a fault
//! in its text, the line: bytes that are not UTF-8 text; a position, normal
//! or texture coordinate with too few numbers or a word that is not a
//! number; a position or normal that is NaN or infinite (a number beyond
//! f32's range reads as infinite), or whose `w` is 0; colours on some
//! positions and not on others; a face with fewer than three vertices, or
//! an index that is 0, not an integer, or names an element not defined
//! before the face line; polylines (`l`); `usemtl` without a name; more
//! than [`MAX_TRIANGLES`] triangles or [`MAX_MESH_VERTICES`] positions,
//! normals or texture coordinates; a file without faces.
//!
//! Every line is checked before tobj parses the text: tobj's own errors
//! name no line, and an index out of range can overflow its arithmetic.
//! The check accepts only text tobj reads the same way. An OBJ file has no
//! end marker: a file cut at the end of a line, or within the last index of
//! a face, reads as a smaller mesh.
//!
//! # Writing
//!
//! [`write_obj`] writes objects ([`ObjObject`]) one after the other: each
//! vertex's coordinates in the shortest decimal that reads back as the same
//! f32 (Rust's `Display` for f32), each face's indices counted across the
//! whole file from 1. Read back, a written file gives every triangle's
//! corners bit for bit; a mesh whose vertices are all used, in the order its
//! triangles first use them, reads back identical.

use super::TriMesh;
use crate::error::{Error, Result};
use crate::input::{self, ReadError};
use crate::limits::{MAX_MESH_FILE_BYTES, MAX_MESH_VERTICES, MAX_TRIANGLES};
use crate::output::{clip_to, printable};
use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// The triangle mesh in the OBJ file at `path` (see the module's rules).
pub fn read_obj(path: &Path) -> Result<TriMesh> {
    let bytes = read_file(path)?;
    parse_obj(&bytes, path)
}

/// The triangle mesh an OBJ file's bytes describe; `path` names the file in
/// errors. More than [`MAX_MESH_FILE_BYTES`] bytes are refused.
pub fn parse_obj(bytes: &[u8], path: &Path) -> Result<TriMesh> {
    parse_within(bytes, path, MAX_MESH_VERTICES, MAX_TRIANGLES)
}

/// [`parse_obj`] with the bounds on vertices and triangles given.
fn parse_within(bytes: &[u8], path: &Path, max_vertices: usize, max_triangles: usize) -> Result<TriMesh> {
    let bad = |message: String| Error::Parse { path: shown_path(path), message };
    if bytes.len() as u64 > MAX_MESH_FILE_BYTES {
        return Err(bad(format!(
            "{} bytes is too large: at most {MAX_MESH_FILE_BYTES} (limits::MAX_MESH_FILE_BYTES)",
            bytes.len()
        )));
    }
    let bom = if bytes.starts_with(b"\xEF\xBB\xBF") { 3 } else { 0 };
    let text = std::str::from_utf8(&bytes[bom..]).map_err(|e| {
        let at = bom + e.valid_up_to();
        let line = 1 + bytes[..at].iter().filter(|&&b| b == b'\n').count();
        bad(format!("line {line}: not UTF-8 text (byte 0x{:02x} at offset {at}); an OBJ file is text", bytes[at]))
    })?;
    let scan =
        Scan::new(max_vertices, max_triangles).run(text).map_err(|(line, what)| bad(format!("line {line}: {what}")))?;
    if scan.triangles == 0 {
        return Err(bad("has no faces (f), so no triangles".into()));
    }
    // The default fills the fields tobj has under its features `merging`
    // and `reordering`, which another crate of a build could turn on.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    // No material file is opened: `mtllib` loads an empty library.
    let (models, _) = tobj::load_obj_buf(&mut text.as_bytes(), &options, |_| Ok(Default::default()))
        .map_err(|e| bad(format!("{e} (tobj)")))?;
    let mesh = merged(models);
    match mesh.fault_within(max_vertices, max_triangles) {
        // What the scan cannot see: more vertices than the bound once the
        // positions met with different normals or texture coordinates are split.
        Some(fault) => Err(bad(format!("the mesh {fault}"))),
        None => Ok(mesh),
    }
}

/// tobj's models as one mesh, in order; normals only if every vertex has one.
fn merged(models: Vec<tobj::Model>) -> TriMesh {
    let vertices = models.iter().map(|m| m.mesh.positions.len() / 3).sum();
    let triangles = models.iter().map(|m| m.mesh.indices.len() / 3).sum();
    let with_normals = models.iter().all(|m| m.mesh.normals.len() == m.mesh.positions.len());
    let mut mesh = TriMesh {
        positions: Vec::with_capacity(vertices),
        triangles: Vec::with_capacity(triangles),
        normals: with_normals.then(|| Vec::with_capacity(vertices)),
    };
    let triple = |v: &[f32]| [v[0], v[1], v[2]];
    for m in models {
        // At most three vertices a triangle, and the scan bounded the
        // triangles: the offset fits u32.
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(m.mesh.positions.chunks_exact(3).map(triple));
        mesh.triangles.extend(m.mesh.indices.chunks_exact(3).map(|t| [base + t[0], base + t[1], base + t[2]]));
        if let Some(normals) = &mut mesh.normals {
            normals.extend(m.mesh.normals.chunks_exact(3).map(triple));
        }
    }
    mesh
}

/// The counts of a text's elements, checked line by line ([`Scan::run`]).
struct Scan {
    positions: usize,
    texcoords: usize,
    normals: usize,
    /// Whether the positions have colours (set by the first).
    coloured: Option<bool>,
    triangles: usize,
    max_vertices: usize,
    max_triangles: usize,
}

/// What a line that is refused is refused for.
type Fault = std::result::Result<(), String>;

impl Scan {
    fn new(max_vertices: usize, max_triangles: usize) -> Scan {
        Scan { positions: 0, texcoords: 0, normals: 0, coloured: None, triangles: 0, max_vertices, max_triangles }
    }

    /// Checks every line of `text` (split as tobj splits it), stopping at
    /// the first fault: its line number (from 1) and what is wrong.
    fn run(mut self, text: &str) -> std::result::Result<Scan, (usize, String)> {
        for (n, line) in text.lines().enumerate() {
            self.line(line).map_err(|what| (n + 1, what))?;
        }
        Ok(self)
    }

    /// One line, split into words as tobj splits it; its first word says
    /// what it is.
    fn line(&mut self, line: &str) -> Fault {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => self.position(words),
            Some("vn") => {
                let n = numbers::<3>(words, "a normal (vn)")?;
                finite(n, "normal")?;
                count(&mut self.normals, self.max_vertices, "normals (vn)")
            }
            Some("vt") => {
                numbers::<2>(words, "a texture coordinate (vt)")?;
                count(&mut self.texcoords, self.max_vertices, "texture coordinates (vt)")
            }
            Some("f") => self.face(words),
            Some("l") => Err("a polyline (l) is not a surface; a mesh is read from faces (f)".into()),
            // tobj takes the name after the first space.
            Some("usemtl") if line.split_once(' ').unwrap_or_default().1.trim().is_empty() => {
                Err("usemtl names no material".into())
            }
            _ => Ok(()),
        }
    }

    /// `v x y z`, `v x y z w` or `v x y z r g b`.
    fn position(&mut self, words: std::str::SplitWhitespace) -> Fault {
        let mut w = [""; 6];
        let mut n = 0;
        for word in words {
            if n < w.len() {
                w[n] = word;
            }
            n += 1;
        }
        if n < 3 {
            return Err(format!("a position (v) needs 3 coordinates, found {n}"));
        }
        let mut p = [number(w[0])?, number(w[1])?, number(w[2])?];
        let coloured = match n {
            3 => false,
            4 => {
                let scale = number(w[3])?;
                if scale == 0.0 {
                    return Err("a position's w (its 4th number) is 0; the coordinates are divided by it".into());
                }
                p = p.map(|x| x / scale);
                false
            }
            6 => {
                for c in &w[3..] {
                    number(c)?;
                }
                true
            }
            _ => {
                return Err(format!("a position (v) has 3 coordinates, then a w or an r g b colour: found {n} numbers"))
            }
        };
        finite(p, "position")?;
        if *self.coloured.get_or_insert(coloured) != coloured {
            return Err("a colour on some positions (v x y z r g b) and not on others: all or none".into());
        }
        count(&mut self.positions, self.max_vertices, "positions (v)")
    }

    /// `f` and three or more vertices, each `v`, `v/vt`, `v//vn` or `v/vt/vn`.
    fn face(&mut self, words: std::str::SplitWhitespace) -> Fault {
        let mut k = 0usize;
        for word in words {
            let mut parts = word.split('/');
            let (v, vt, vn) = (parts.next().unwrap_or_default(), parts.next(), parts.next());
            if parts.next().is_some() {
                return Err(format!("'{}' is not a face vertex (v, v/vt, v//vn or v/vt/vn)", shown(word)));
            }
            if v.is_empty() {
                return Err(format!("'{}' has no position index", shown(word)));
            }
            index(v, self.positions, "position")?;
            if let Some(vt) = vt.filter(|s| !s.is_empty()) {
                index(vt, self.texcoords, "texture coordinate")?;
            }
            if let Some(vn) = vn.filter(|s| !s.is_empty()) {
                index(vn, self.normals, "normal")?;
            }
            k += 1;
        }
        if k < 3 {
            return Err(format!("a face (f) needs 3 or more vertices, found {k}"));
        }
        self.triangles += k - 2;
        if self.triangles > self.max_triangles {
            return Err(format!(
                "more than {} triangles (polygons split into triangles); at most {} (limits::MAX_TRIANGLES)",
                self.max_triangles, self.max_triangles
            ));
        }
        Ok(())
    }
}

/// The first `N` words as f32 (as tobj reads them); more are ignored.
fn numbers<const N: usize>(mut words: std::str::SplitWhitespace, what: &str) -> std::result::Result<[f32; N], String> {
    let mut out = [0.0; N];
    for (k, x) in out.iter_mut().enumerate() {
        let word = words.next().ok_or_else(|| format!("{what} needs {N} numbers, found {k}"))?;
        *x = number(word)?;
    }
    Ok(out)
}

fn number(word: &str) -> std::result::Result<f32, String> {
    word.parse().map_err(|_| format!("'{}' is not a number", shown(word)))
}

fn finite(v: [f32; 3], what: &str) -> Fault {
    if v.iter().all(|x| x.is_finite()) {
        return Ok(());
    }
    Err(format!("a {what} must be finite, got {v:?} (a number beyond f32's range, about 3.4e38, is infinite)"))
}

/// One more element of a kind, at most `max` of them.
fn count(n: &mut usize, max: usize, what: &str) -> Fault {
    *n += 1;
    if *n > max {
        return Err(format!("more than {max} {what}; at most {max} (limits::MAX_MESH_VERTICES)"));
    }
    Ok(())
}

/// A face's index of a `what`, `defined` of them before its line: from 1 up,
/// or back from -1 (the last).
fn index(word: &str, defined: usize, what: &str) -> Fault {
    let i: isize = word.parse().map_err(|_| format!("'{}' is not a {what} index", shown(word)))?;
    if i == 0 {
        return Err(format!("{what} index 0: indices count from 1 (or back from -1)"));
    }
    if i.unsigned_abs() > defined {
        let which = if i > 0 { "" } else { "relative " };
        return Err(format!("{which}{what} index {i} but {defined} are defined before this line"));
    }
    Ok(())
}

/// Reads the regular file at `path`, at most [`MAX_MESH_FILE_BYTES`] of it.
fn read_file(path: &Path) -> Result<Vec<u8>> {
    let name = shown_path(path).display().to_string();
    let refuse = |what: String| Error::Input(format!("mesh file {name} {what}"));
    let found = input::open_regular(path)
        .map_err(|u| refuse(u.describe("not a file")))?
        .ok_or_else(|| refuse("cannot be read: no such file".into()))?;
    input::read_bounded(&found.file, &found.meta, MAX_MESH_FILE_BYTES).map_err(|e| match e {
        ReadError::TooLarge(size) => refuse(format!(
            "is too large: {} bytes, at most {MAX_MESH_FILE_BYTES} (limits::MAX_MESH_FILE_BYTES)",
            size.map_or_else(|| format!("more than {MAX_MESH_FILE_BYTES} (it grew while read)"), |s| s.to_string())
        )),
        ReadError::Io(e) => refuse(format!("cannot be read: {e}")),
    })
}

/// A word of a file for a message: [`printable`], at most 40 characters.
fn shown(text: &str) -> String {
    clip_to(&printable(text), 40)
}

/// A path as messages show it: [`printable`] if it needs to be.
fn shown_path(path: &Path) -> PathBuf {
    match path.to_str() {
        Some(text) if printable(text) == text => path.to_path_buf(),
        _ => PathBuf::from(printable(&path.display().to_string()).into_owned()),
    }
}

/// One object of an OBJ file [`write_obj`] writes: its name (`o name`), a
/// comment under it, its positions, and its triangles as indices into its
/// own positions (from 0).
#[derive(Clone, Copy, Debug)]
pub struct ObjObject<'a> {
    pub name: &'a str,
    pub comment: &'a str,
    pub positions: &'a [[f32; 3]],
    pub triangles: &'a [[u32; 3]],
}

/// Writes `objects` as an OBJ file: `header` as comment lines (`# `, one a
/// line of it), then each object: `o name`, its comment, a `v x y z` line a
/// position (the shortest decimal that reads back as the same f32), an
/// `f a b c` line a triangle, its indices counted across the whole file
/// from 1. Refuses (`InvalidInput`, before writing anything) what would make
/// a file [`parse_obj`] refuses or misreads: a name that is empty, has
/// surrounding spaces or a control character; a header or comment with a
/// control character other than a line break or tab; a coordinate that is
/// NaN or infinite; an index past the object's positions. (The bounds of
/// [`crate::limits`] are the reader's.)
pub fn write_obj(w: &mut impl Write, header: &str, objects: &[ObjObject]) -> io::Result<()> {
    let invalid = |what: String| io::Error::new(io::ErrorKind::InvalidInput, what);
    let bad_text = |s: &str| s.chars().any(|c| c.is_control() && c != '\n' && c != '\t');
    if bad_text(header) {
        return Err(invalid("OBJ header has a control character".into()));
    }
    for o in objects {
        let name = shown(o.name);
        if o.name.is_empty() || o.name.trim() != o.name || o.name.chars().any(char::is_control) {
            return Err(invalid(format!(
                "OBJ object name '{name}': empty, surrounded by spaces or with a control character"
            )));
        }
        if bad_text(o.comment) {
            return Err(invalid(format!("OBJ object {name}: its comment has a control character")));
        }
        if let Some(i) = o.positions.iter().position(|p| !p.iter().all(|x| x.is_finite())) {
            return Err(invalid(format!("OBJ object {name}: position {i} is not finite: {:?}", o.positions[i])));
        }
        let n = o.positions.len();
        if let Some(t) = o.triangles.iter().position(|t| t.iter().any(|&i| i as usize >= n)) {
            return Err(invalid(format!(
                "OBJ object {name}: triangle {t} {:?} has an index past its {n} positions",
                o.triangles[t]
            )));
        }
    }
    let mut out = io::BufWriter::new(w);
    for line in header.lines() {
        writeln!(out, "# {line}")?;
    }
    let mut base = 1u64;
    for o in objects {
        writeln!(out, "o {}", o.name)?;
        for line in o.comment.lines() {
            writeln!(out, "# {line}")?;
        }
        for [x, y, z] in o.positions {
            writeln!(out, "v {x} {y} {z}")?;
        }
        for t in o.triangles {
            let [a, b, c] = t.map(|i| base + u64::from(i));
            writeln!(out, "f {a} {b} {c}")?;
        }
        base += o.positions.len() as u64;
    }
    out.flush()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::{place, unit_icosphere};
    use proptest::prelude::*;

    fn parse(text: &str) -> Result<TriMesh> {
        parse_obj(text.as_bytes(), Path::new("m.obj"))
    }

    /// The message for `text`, which must be refused.
    fn refused(text: &str) -> String {
        parse(text).unwrap_err().to_string()
    }

    /// `mesh` with its vertices renumbered in the order its triangles first
    /// use them, unused ones dropped: what reading it back from OBJ gives.
    fn first_use_order(mesh: &TriMesh) -> TriMesh {
        let mut new = vec![u32::MAX; mesh.positions.len()];
        let mut out = TriMesh { normals: None, ..Default::default() };
        for t in &mesh.triangles {
            out.triangles.push(t.map(|i| {
                if new[i as usize] == u32::MAX {
                    new[i as usize] = out.positions.len() as u32;
                    out.positions.push(mesh.positions[i as usize]);
                }
                new[i as usize]
            }));
        }
        out
    }

    fn bits(positions: &[[f32; 3]]) -> Vec<u32> {
        positions.iter().flatten().map(|x| x.to_bits()).collect()
    }

    fn written(header: &str, objects: &[ObjObject]) -> String {
        let mut out = Vec::new();
        write_obj(&mut out, header, objects).unwrap();
        String::from_utf8(out).unwrap()
    }

    const CUBE: &str = "# a unit cube of quads, normals per face
o cube
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
vt 0 0
vt 1 0
vt 1 1
vn 0 0 -1
vn 0 0 1
f 1/1/1 4/2/1 3/3/1 2/3/1
f 5//2 6//2 7//2 8//2
g sides
f 1 2 6 5
f 2 3 7 6
f -5 -1 -2 -6
f 4 1 5 8
";

    #[test]
    fn objects_and_groups_merge_and_polygons_split_into_fans() {
        let m = parse(CUBE).unwrap();
        assert_eq!(m.triangles.len(), 12);
        assert_eq!(m.signed_volume(), 1.0, "outward faces, one closed cube");
        // The first quad: fan (1 4 3), (1 3 2), first-use numbering.
        assert_eq!(&m.triangles[..2], &[[0, 1, 2], [0, 2, 3]]);
        assert_eq!(&m.positions[..4], &[[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0], [1.0, 0.0, 0.0]]);
        // Some vertices have no normal: none kept. Positions met with
        // normals in the first object are vertices again in the second.
        assert_eq!(m.normals, None);
        assert_eq!(m.positions.len(), 8 + 8);
        m.check().unwrap();
    }

    #[test]
    fn normals_are_kept_when_every_vertex_has_one() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 -1\nf 1//1 2//1 3//1\nf 1//2 3//2 2//2\n";
        let m = parse(text).unwrap();
        assert_eq!(m.positions.len(), 6, "a position with two normals is two vertices");
        assert_eq!(m.triangles, vec![[0, 1, 2], [3, 4, 5]]);
        assert_eq!(
            m.normals.unwrap(),
            [[0.0, 0.0, 1.0]; 3].into_iter().chain([[0.0, 0.0, -1.0]; 3]).collect::<Vec<_>>()
        );
        // A w divides; colours and texture coordinates are dropped; a BOM
        // and CRLF line ends are fine; materials are not loaded.
        let text = "\u{feff}mtllib none.mtl\r\nusemtl red\r\nv 0 0 0 2\r\nv 2 0 0 2\r\nv 0 4 0 2\r\nf 1 2 3\r\n";
        let m = parse(text).unwrap();
        assert_eq!(m.positions, vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 2.0, 0.0]]);
        let m = parse("v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nvt 0.5 0.5 0\nf 1/1 2/1 3/1\n").unwrap();
        assert_eq!((m.positions.len(), m.normals), (3, None));
    }

    #[test]
    fn what_is_written_reads_back_bit_for_bit() {
        let (unit, tris) = unit_icosphere(2).unwrap();
        let a = place(&unit, [1.25, -3.5, 0.1], 0.7);
        let b = place(&unit, [-123456.7, 0.001, 9876.5], -3.3e-3);
        // Extremes of f32: the smallest subnormal, the largest finite, -0.
        let odd = [[f32::from_bits(1), -f32::MAX, -0.0], [f32::MAX, 1e-38, 3.4028e-30], [0.1, -7e-45, 16777217.0]];
        let objects = [
            ObjObject {
                name: "sphere_0",
                comment: "centre [1.25, -3.5, 0.1], radius 0.7",
                positions: &a,
                triangles: &tris,
            },
            ObjObject { name: "sphere_1", comment: "hollow", positions: &b, triangles: &tris },
            ObjObject { name: "odd one", comment: "", positions: &odd, triangles: &[[0, 2, 1]] },
        ];
        let text = written("rtow icospheres\nlevel 2", &objects);
        assert!(
            text.starts_with("# rtow icospheres\n# level 2\no sphere_0\n# centre [1.25, -3.5, 0.1], radius 0.7\nv ")
        );
        let [a0, b0, c0] = tris[0].map(|i| i + 1 + 162);
        assert!(text.contains("\no sphere_1\n# hollow\nv "));
        assert!(text.contains(&format!("\nf {a0} {b0} {c0}\n")), "global indices from 1");
        let m = parse(&text).unwrap();
        // Corner by corner, bit for bit.
        let corners = |m: &TriMesh| (0..m.triangles.len()).flat_map(|t| m.corners(t)).collect::<Vec<_>>();
        let whole = TriMesh {
            positions: [&a[..], &b, &odd].concat(),
            triangles: tris
                .iter()
                .copied()
                .chain(tris.iter().map(|t| t.map(|i| i + a.len() as u32)))
                .chain([[0, 2, 1].map(|i| i + 2 * a.len() as u32)])
                .collect(),
            normals: None,
        };
        assert_eq!(bits(&corners(&m)), bits(&corners(&whole)));
        // And vertex by vertex, in first-use order.
        let expected = first_use_order(&whole);
        assert_eq!(bits(&m.positions), bits(&expected.positions));
        assert_eq!(m.triangles, expected.triangles);
        // A mesh already in first-use order reads back identical.
        let again = parse(&written(
            "",
            &[ObjObject { name: "s", comment: "", positions: &m.positions, triangles: &m.triangles }],
        ))
        .unwrap();
        assert_eq!(bits(&again.positions), bits(&m.positions));
        assert_eq!(again.triangles, m.triangles);
    }

    #[test]
    fn the_writer_refuses_what_the_reader_would_refuse() {
        let p = [[0.0f32; 3]; 3];
        let write = |o: ObjObject| {
            let mut out = Vec::new();
            let e = write_obj(&mut out, "h", &[o]).unwrap_err();
            assert!(out.is_empty(), "nothing written");
            assert_eq!(e.kind(), io::ErrorKind::InvalidInput);
            e.to_string()
        };
        let ok = ObjObject { name: "a", comment: "", positions: &p, triangles: &[[0, 1, 2]] };
        assert_eq!(
            write(ObjObject { triangles: &[[0, 1, 3]], ..ok }),
            "OBJ object a: triangle 0 [0, 1, 3] has an index past its 3 positions"
        );
        let nan = [[0.0, f32::NAN, 0.0]];
        assert_eq!(
            write(ObjObject { positions: &nan, triangles: &[], ..ok }),
            "OBJ object a: position 0 is not finite: [0.0, NaN, 0.0]"
        );
        assert!(write(ObjObject { name: "a\nv 1 2 3", ..ok }).starts_with("OBJ object name 'a\\nv 1 2 3'"));
        assert!(write(ObjObject { name: "", ..ok }).contains("empty"));
        assert!(write(ObjObject { name: " a", ..ok }).contains("spaces"));
        assert!(write(ObjObject { comment: "a\rb", ..ok }).contains("comment"));
        assert!(write_obj(&mut Vec::new(), "a\u{1b}[2J", &[ok]).is_err());
        // A comment of several lines is several comment lines.
        let text = written("", &[ObjObject { comment: "one\ntwo", ..ok }]);
        assert_eq!(text, "o a\n# one\n# two\nv 0 0 0\nv 0 0 0\nv 0 0 0\nf 1 2 3\n");
    }

    #[test]
    fn damaged_files_are_refused_naming_the_file_and_the_line() {
        let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        let cases: &[(&str, &str)] = &[
            ("", "m.obj: has no faces (f), so no triangles"),
            ("# nothing\n\no empty\n", "m.obj: has no faces (f), so no triangles"),
            ("v 1 nan 2\n", "m.obj: line 1: a position must be finite, got [1.0, NaN, 2.0]"),
            ("v 1 2 -inf\n", "m.obj: line 1: a position must be finite, got [1.0, 2.0, -inf]"),
            ("v 1 2 1e39\n", "m.obj: line 1: a position must be finite, got [1.0, 2.0, inf]"),
            ("v 1 0 0 1e-30\nv 1e30 0 0 1e-30\n", "m.obj: line 2: a position must be finite, got [inf, 0.0, 0.0]"),
            ("v 1 2 3 0\n", "m.obj: line 1: a position's w (its 4th number) is 0"),
            ("v 1 2\n", "m.obj: line 1: a position (v) needs 3 coordinates, found 2"),
            ("v 1 2 3 4 5\n", "m.obj: line 1: a position (v) has 3 coordinates, then a w or an r g b colour: found 5"),
            ("v 1 2 3 # a comment\n", "m.obj: line 1: '#' is not a number"),
            ("v 1 x 3\n", "m.obj: line 1: 'x' is not a number"),
            ("v 1 2 3 1 0 0\nv 1 2 3\n", "m.obj: line 2: a colour on some positions (v x y z r g b) and not on others"),
            ("vn 0 1\n", "m.obj: line 1: a normal (vn) needs 3 numbers, found 2"),
            ("vn 0 1 nan\n", "m.obj: line 1: a normal must be finite, got [0.0, 1.0, NaN]"),
            ("vt 0\n", "m.obj: line 1: a texture coordinate (vt) needs 2 numbers, found 1"),
            ("f 1 2 3\n", "m.obj: line 1: position index 1 but 0 are defined before this line"),
            ("v 0 0 0\nv 1 0 0\nf 1 2 9\n", "m.obj: line 3: position index 9 but 2 are defined before this line"),
            ("v 0 0 0\nf 1 -2 1\n", "m.obj: line 2: relative position index -2 but 1 are defined before this line"),
            ("v 0 0 0\nf 1 0 1\n", "m.obj: line 2: position index 0: indices count from 1 (or back from -1)"),
            ("v 0 0 0\nf 1 1 99999999999999999999\n", "m.obj: line 2: '99999999999999999999' is not a position index"),
            ("v 0 0 0\nf 1 1 9223372036854775807\n", "m.obj: line 2: position index 9223372036854775807 but 1 are"),
            (
                "v 0 0 0\nf 1 1 -9223372036854775808\n",
                "m.obj: line 2: relative position index -9223372036854775808 but 1",
            ),
            ("v 0 0 0\nf 1 1 1.5\n", "m.obj: line 2: '1.5' is not a position index"),
            ("v 0 0 0\nf 1 1 #\n", "m.obj: line 2: '#' is not a position index"),
            ("v 0 0 0\nf 1 1 1/1/1/1\n", "m.obj: line 2: '1/1/1/1' is not a face vertex"),
            ("v 0 0 0\nf 1 1 //1\n", "m.obj: line 2: '//1' has no position index"),
            ("v 0 0 0\nvt 0 0\nf 1/1 1/0 1/1\n", "m.obj: line 3: texture coordinate index 0"),
            ("v 0 0 0\nvt 0 0\nf 1/1 1/-2 1/1\n", "m.obj: line 3: relative texture coordinate index -2 but 1"),
            ("v 0 0 0\nf 1/1 1/1 1/1\n", "m.obj: line 2: texture coordinate index 1 but 0 are defined"),
            ("v 0 0 0\nvn 0 0 1\nf 1//1 1//2 1//1\n", "m.obj: line 3: normal index 2 but 1 are defined"),
            ("v 0 0 0\nvn 0 0 1\nf 1//1 1//-9223372036854775808 1//1\n", "m.obj: line 3: relative normal index"),
            ("v 0 0 0\nf 1 1\n", "m.obj: line 2: a face (f) needs 3 or more vertices, found 2"),
            ("v 0 0 0\nf\n", "m.obj: line 2: a face (f) needs 3 or more vertices, found 0"),
            ("v 0 0 0\nl 1 1 1\n", "m.obj: line 2: a polyline (l) is not a surface"),
            ("v 0 0 0\nusemtl\n", "m.obj: line 2: usemtl names no material"),
            ("v 0 0 0\nusemtl\tred\n", "m.obj: line 2: usemtl names no material"),
        ];
        for (text, want) in cases {
            let e = parse(text).unwrap_err();
            assert_eq!(e.exit_code(), 2);
            assert!(e.to_string().starts_with(want), "{text:?}: {e}\n  wanted {want}");
        }
        assert!(parse(&format!("{tri}f 1 2 3\n")).is_ok());
        // Not text: the first bad byte, its line and offset.
        let mut garbage = b"v 0 0 0\nv 1 0 0\n".to_vec();
        garbage.extend([0xff, 0xfe, 0x00, 0x13, 0x80, b'f', 0xc3]);
        let e = parse_obj(&garbage, Path::new("m.obj")).unwrap_err().to_string();
        assert_eq!(e, "m.obj: line 3: not UTF-8 text (byte 0xff at offset 16); an OBJ file is text");
        let png = b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR\0\0\0\x01";
        assert!(parse_obj(png, Path::new("m.obj")).unwrap_err().to_string().starts_with("m.obj: line 1: not UTF-8"));
        // Text, but not OBJ: no faces.
        assert_eq!(refused("\u{1b}[2J hello\nworld\0\n"), "m.obj: has no faces (f), so no triangles");
        // A word quoted in a message is escaped and clipped.
        let e = refused(&format!("v 0 0 \u{1b}[2J{}\n", "9".repeat(100)));
        assert!(
            e.starts_with("m.obj: line 1: '\\u{1b}[2J999") && e.contains("...' is not a number") && e.len() < 120,
            "{e}"
        );
    }

    #[test]
    fn a_file_cut_anywhere_is_refused_or_reads_as_a_smaller_mesh() {
        let (unit, tris) = unit_icosphere(1).unwrap();
        let p = place(&unit, [0.5, 0.25, -2.0], 1.5);
        let text = written("cut", &[ObjObject { name: "s", comment: "", positions: &p, triangles: &tris }]);
        let whole = parse(&text).unwrap();
        let faces_start = text.find("\nf ").unwrap();
        let (mut errors, mut smaller) = (0, 0);
        for n in 0..text.len() {
            match parse(&text[..n]) {
                Err(e) => {
                    assert!(e.to_string().starts_with("m.obj: "), "{e}");
                    errors += 1;
                }
                Ok(m) => {
                    // Only a cut among the faces reads: a prefix of them.
                    assert!(n > faces_start, "cut at {n} read");
                    assert!(m.triangles.len() <= whole.triangles.len());
                    m.check().unwrap();
                    smaller += 1;
                }
            }
        }
        assert!(errors > faces_start && smaller > 0);
        // Cut inside the positions: no faces, or a position of too few numbers.
        assert_eq!(refused(&text[..faces_start / 2]), "m.obj: has no faces (f), so no triangles");
        let cut = text[..text.find("\nv ").unwrap() + 6].to_string();
        assert!(parse(&cut).unwrap_err().to_string().contains("line 3: a position (v) needs 3 coordinates"), "{cut}");
        // Cut inside a face: too few vertices.
        let cut = &text[..faces_start + 5];
        assert!(parse(cut).unwrap_err().to_string().contains("a face (f) needs 3 or more vertices, found 1"), "{cut}");
    }

    #[test]
    fn the_bounds_are_checked_while_scanning() {
        let within = |text: &str, v, t| parse_within(text.as_bytes(), Path::new("m.obj"), v, t);
        let quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";
        assert_eq!(within(quad, 4, 2).unwrap().triangles.len(), 2);
        let e = within(quad, 3, 2).unwrap_err().to_string();
        assert_eq!(e, "m.obj: line 4: more than 3 positions (v); at most 3 (limits::MAX_MESH_VERTICES)");
        let e = within(quad, 4, 1).unwrap_err().to_string();
        assert_eq!(
            e,
            "m.obj: line 5: more than 1 triangles (polygons split into triangles); at most 1 (limits::MAX_TRIANGLES)"
        );
        let e = within("vn 0 0 1\nvn 0 0 1\n", 1, 1).unwrap_err().to_string();
        assert!(e.starts_with("m.obj: line 2: more than 1 normals (vn)"), "{e}");
        // The real bound, by one polygon of MAX_TRIANGLES + 1 triangles.
        let mut big = String::from("v 0 0 0\nf");
        big.extend(std::iter::repeat_n(" 1", MAX_TRIANGLES + 3));
        let e = refused(&big);
        assert!(e.starts_with(&format!("m.obj: line 2: more than {MAX_TRIANGLES} triangles")), "{e}");
        // The mesh read is held to the vertex bound too (split positions).
        let e = within("v 0 0 0\nv 1 0 0\nvn 0 0 1\nvn 0 1 0\nf 1//1 1//2 2//1\n", 2, 9).unwrap_err().to_string();
        assert_eq!(e, "m.obj: the mesh has 3 vertices; at most 2 (limits::MAX_MESH_VERTICES)");
    }

    #[test]
    fn paths_that_are_not_files_are_refused_before_reading() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let e = read_obj(&d.join("none.obj")).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().starts_with(&format!("mesh file {} cannot be read: ", d.join("none.obj").display())));
        let e = read_obj(d).unwrap_err().to_string();
        assert_eq!(e, format!("mesh file {} is a folder, not a file", d.display()));
        let big = d.join("big.obj");
        std::fs::File::create(&big).unwrap().set_len(MAX_MESH_FILE_BYTES + 1).unwrap();
        let e = read_obj(&big).unwrap_err().to_string();
        assert!(e.ends_with("is too large: 268435457 bytes, at most 268435456 (limits::MAX_MESH_FILE_BYTES)"), "{e}");
        std::fs::write(d.join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        assert_eq!(read_obj(&d.join("tri.obj")).unwrap().triangles, vec![[0, 1, 2]]);
        std::fs::write(d.join("bad\u{1b}[31m.obj"), "f 1 2 3\n").unwrap();
        let e = read_obj(&d.join("bad\u{1b}[31m.obj")).unwrap_err().to_string();
        assert!(e.ends_with("bad\\u{1b}[31m.obj: line 1: position index 1 but 0 are defined before this line"), "{e}");
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(d.join("gone.obj"), d.join("link.obj")).unwrap();
            let e = read_obj(&d.join("link.obj")).unwrap_err().to_string();
            assert!(e.ends_with("link.obj is a symbolic link to a file that does not exist"), "{e}");
            let fifo = d.join("fifo.obj");
            let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
            assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
            let e = read_obj(&fifo).unwrap_err().to_string();
            assert!(e.ends_with("fifo.obj is a FIFO (named pipe), not a file"), "{e}");
            let e = read_obj(Path::new("/dev/null")).unwrap_err().to_string();
            assert_eq!(e, "mesh file /dev/null is a device, not a file");
        }
    }

    /// Words that reach the parser's corners: indices out of range, 0,
    /// overflowing, non-numbers, statements.
    const NASTY: &[&str] = &[
        "0",
        "-1",
        "-9",
        "9",
        "1/0",
        "1//0",
        "1/-9/2",
        "1/1/1/1",
        "//",
        "/",
        "nan",
        "inf",
        "-inf",
        "1e39",
        "1e-45",
        "99999999999999999999",
        "-9223372036854775808",
        "9223372036854775807",
        "f",
        "v",
        "vn",
        "vt",
        "l",
        "o",
        "g",
        "usemtl",
        "mtllib",
        "#",
        "\n",
        "\r",
        "\u{feff}",
        "\u{ff}",
        "3.5",
        "",
    ];

    const SMALL: &str = "# small\nmtllib a.mtl\no one\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0 1\nvt 0 0\nvt 1 1\n\
        vn 0 0 1\nusemtl red\nf 1/1/1 2/2/1 3/2/1\nf -4 -2 -1\ng two\nv 0 0 1\nf 1 2 5 4\ns off\n";

    proptest! {
        #![proptest_config(ProptestConfig { cases: 1000, ..ProptestConfig::default() })]

        #[test]
        fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
            if let Err(e) = parse_obj(&bytes, Path::new("r.obj")) {
                prop_assert!(e.to_string().starts_with("r.obj: "));
            }
        }

        #[test]
        fn mutated_files_never_panic_and_what_is_read_is_usable(
            words in proptest::collection::vec((any::<prop::sample::Index>(), prop::sample::select(NASTY)), 0..4),
            edits in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>(), 0..3u8), 0..6),
        ) {
            let mut tokens: Vec<String> = SMALL.split(' ').map(str::to_string).collect();
            for (at, word) in &words {
                let i = at.index(tokens.len());
                tokens[i] = word.to_string();
            }
            let mut bytes = tokens.join(" ").into_bytes();
            for (at, byte, how) in &edits {
                let i = at.index(bytes.len());
                match how {
                    0 => bytes[i] = *byte,
                    1 => bytes.insert(i, *byte),
                    _ => { bytes.remove(i); }
                }
            }
            match parse_obj(&bytes, Path::new("r.obj")) {
                Ok(m) => prop_assert!(m.fault().is_none(), "{:?}", m.fault()),
                Err(e) => prop_assert!(e.to_string().starts_with("r.obj: ")),
            }
        }
    }
}
