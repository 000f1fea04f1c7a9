//! A PDF figure's provenance in its document information dictionary, added as an incremental
//! update (PDF 1.7, 7.5.6): a new `/Info` object, a cross-reference section for it and a
//! trailer that points back to the file's own (`/Prev`), appended after the file's `%%EOF`.
//! The bytes svg2pdf wrote are kept as they are; a reader takes the newest trailer's `/Info`.

use capstan_data::Provenance;

/// `pdf` with `/Title` (`title`), `/Subject` (the provenance line), `/Keywords` (commit, input
/// SHA-256), `/Creator` (program and commit) and `/Producer` in a new document information
/// dictionary; None when its last trailer is not one this module can read (no `/Size`,
/// `/Root` or `startxref`).
pub fn with_info(pdf: &[u8], title: &str, p: &Provenance) -> Option<Vec<u8>> {
    let text = String::from_utf8_lossy(pdf);
    let tail = &text[text.rfind("trailer")?..];
    let size: usize = number_after(tail, "/Size")?.parse().ok()?;
    let root = number_after(tail, "/Root")?;
    let prev = number_after(&text[text.rfind("startxref")?..], "startxref")?;
    let id = tail.find("/ID").map(|k| {
        let end = tail[k..].find(']').map_or(tail.len(), |e| k + e + 1);
        format!("\n  {}", &tail[k..end])
    });
    let mut keywords = format!("capstan; commit {}", p.commit);
    if let Some(h) = &p.input_sha256 {
        keywords.push_str(&format!("; input SHA-256 {h}"));
    }
    let entries = [
        ("Title", title.to_string()),
        ("Subject", p.line()),
        ("Keywords", keywords),
        ("Creator", format!("{} (commit {})", p.program, p.commit)),
        ("Producer", "svg2pdf".to_string()),
    ];
    let mut out = pdf.to_vec();
    if !out.ends_with(b"\n") {
        out.push(b'\n');
    }
    let at = out.len();
    out.extend(format!("{size} 0 obj\n<<\n").bytes());
    for (key, value) in entries {
        out.extend(format!("  /{key} {}\n", text_string(&value)).bytes());
    }
    out.extend(b">>\nendobj\n");
    let xref = out.len();
    out.extend(
        format!(
            "xref\n{size} 1\n{at:010} 00000 n\r\ntrailer\n<<\n  /Size {}\n  /Root {root} 0 R\n  \
             /Info {size} 0 R\n  /Prev {prev}{}\n>>\nstartxref\n{xref}\n%%EOF",
            size + 1,
            id.unwrap_or_default()
        )
        .bytes(),
    );
    Some(out)
}

/// The first whole number after `key` in `text`.
fn number_after<'a>(text: &'a str, key: &str) -> Option<&'a str> {
    let rest = text[text.find(key)? + key.len()..].trim_start();
    let end = rest
        .find(|c: char| !c.is_ascii_digit())
        .unwrap_or(rest.len());
    (end > 0).then(|| &rest[..end])
}

/// A PDF text string: a literal string for printable ASCII (`\`, `(` and `)` escaped), else
/// UTF-16BE with its byte-order mark in hex (PDF 1.7, 7.9.2.2).
fn text_string(s: &str) -> String {
    if s.chars().all(|c| (' '..='~').contains(&c)) {
        let escaped = s
            .replace('\\', "\\\\")
            .replace('(', "\\(")
            .replace(')', "\\)");
        format!("({escaped})")
    } else {
        let hex: String = s.encode_utf16().map(|u| format!("{u:04X}")).collect();
        format!("<FEFF{hex}>")
    }
}

/// The document information dictionary a reader finds in `pdf` (for tests and users'
/// scripts): the last `startxref` → its cross-reference section → the offset of the trailer's
/// `/Info` object, which must begin there; the text of that object. Offsets are of bytes (a
/// PDF's streams are binary).
pub fn document_info(pdf: &[u8]) -> Option<String> {
    let at = |from: usize| String::from_utf8_lossy(&pdf[from.min(pdf.len())..]).into_owned();
    let last = pdf.windows(9).rposition(|w| w == b"startxref")?;
    let xref: usize = number_after(&at(last), "startxref")?.parse().ok()?;
    let section = at(xref);
    let section = section.strip_prefix("xref")?;
    let trailer = &section[section.find("trailer")?..];
    let info: usize = number_after(trailer, "/Info")?.parse().ok()?;
    let mut lines = section.lines().map(str::trim).filter(|l| !l.is_empty());
    let mut header = lines.next()?.split_whitespace();
    let first: usize = header.next()?.parse().ok()?;
    let count: usize = header.next()?.parse().ok()?;
    if !(first..first + count).contains(&info) {
        return None;
    }
    let entry = lines.nth(info - first)?;
    let offset: usize = entry.split_whitespace().next()?.parse().ok()?;
    let object = at(offset);
    let object = object.strip_prefix(&format!("{info} 0 obj"))?;
    Some(object[..object.find("endobj")?].to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A one-page PDF as pdf-writer ends one: objects, xref, trailer with `/Info`.
    fn minimal() -> Vec<u8> {
        let mut pdf = b"%PDF-1.7\n".to_vec();
        let mut offsets = Vec::new();
        for (n, body) in [
            (1, "<< /Type /Catalog /Pages 2 0 R >>"),
            (2, "<< /Type /Pages /Kids [] /Count 0 >>"),
            (3, "<< /Producer (svg2pdf) >>"),
        ] {
            offsets.push(pdf.len());
            pdf.extend(format!("{n} 0 obj\n{body}\nendobj\n\n").bytes());
        }
        let xref = pdf.len();
        pdf.extend(b"xref\n0 4\n0000000000 65535 f\r\n");
        for o in offsets {
            pdf.extend(format!("{o:010} 00000 n\r\n").bytes());
        }
        pdf.extend(
            format!("trailer\n<<\n  /Size 4\n  /Root 1 0 R\n  /Info 3 0 R\n>>\nstartxref\n{xref}\n%%EOF")
                .bytes(),
        );
        pdf
    }

    #[test]
    fn the_newest_info_holds_the_provenance_and_the_file_is_kept() {
        let pdf = minimal();
        assert!(document_info(&pdf).unwrap().contains("(svg2pdf)"));
        let p = Provenance {
            input: Some("données (1).csv".into()),
            input_sha256: Some("ab12".into()),
            ..super::super::tests::provenance()
        };
        let out = with_info(&pdf, "figure-1-gain", &p).unwrap();
        assert!(out.starts_with(&pdf), "the original bytes are kept");
        let info = document_info(&out).unwrap();
        assert!(info.contains("/Title (figure-1-gain)"), "{info}");
        assert!(info.contains("input SHA-256 ab12)"), "{info}");
        assert!(info.contains(&format!("commit {}", p.commit)), "{info}");
        // The subject names a non-ASCII path: UTF-16BE, with its byte-order mark.
        assert!(info.contains("/Subject <FEFF"), "{info}");
        let tail = String::from_utf8_lossy(&out[pdf.len()..]).to_string();
        assert!(
            tail.contains("/Size 5") && tail.contains("/Root 1 0 R"),
            "{tail}"
        );
        let prev = String::from_utf8_lossy(&pdf);
        let old_xref = prev[prev.rfind("startxref").unwrap() + 10..].trim_end_matches("\n%%EOF");
        assert!(tail.contains(&format!("/Prev {old_xref}")), "{tail}");
        assert!(tail.ends_with("%%EOF"));
    }

    #[test]
    fn text_strings_escape_what_pdf_reads_as_syntax() {
        assert_eq!(text_string("a(b)\\c"), "(a\\(b\\)\\\\c)");
        assert_eq!(text_string("é"), "<FEFF00E9>");
    }

    #[test]
    fn a_file_without_a_trailer_is_not_touched() {
        let p = super::super::tests::provenance();
        assert!(with_info(b"%PDF-1.7\nnothing", "x", &p).is_none());
    }
}
