//! A figure file with the provenance of the result it shows inside it, in each format's own
//! metadata: SVG a `<metadata>` element, PNG an `iTXt` chunk, PDF its document information
//! dictionary ([`pdf::with_info`]). Hand-written: each is a few bytes appended in a place the
//! format defines, where a PNG or PDF library would decode and re-encode the whole file.

use capstan_data::Provenance;

pub mod pdf;

/// A figure file with its provenance inside (`name` says the format): an SVG gets a
/// `<metadata id="capstan-provenance">` element, a PNG an `iTXt` chunk (keyword `Comment`,
/// UTF-8) before its end, a PDF a document information dictionary (title, subject, keywords,
/// creator: [`pdf::with_info`]).
pub fn figure(name: &str, bytes: Vec<u8>, p: &Provenance) -> Vec<u8> {
    let line = p.line();
    if name.ends_with(".svg") {
        let text = String::from_utf8_lossy(&bytes);
        let Some(end) = text
            .find("<svg")
            .and_then(|s| text[s..].find('>').map(|e| s + e + 1))
        else {
            return bytes;
        };
        let escaped = line
            .replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('>', "&gt;");
        format!(
            "{}<metadata id=\"capstan-provenance\">{escaped}</metadata>{}",
            &text[..end],
            &text[end..]
        )
        .into_bytes()
    } else if name.ends_with(".png") {
        png_with_text(bytes, "Comment", &line)
    } else if let Some(stem) = name.strip_suffix(".pdf") {
        let title = stem.rsplit('/').next().unwrap_or(stem);
        pdf::with_info(&bytes, title, p).unwrap_or(bytes)
    } else {
        bytes
    }
}

/// `png` with an `iTXt` chunk (`keyword`, uncompressed UTF-8 `text`) before its `IEND`.
fn png_with_text(png: Vec<u8>, keyword: &str, text: &str) -> Vec<u8> {
    const IEND_LEN: usize = 12;
    if png.len() < 8 + IEND_LEN || &png[png.len() - 8..png.len() - 4] != b"IEND" {
        return png;
    }
    let mut data = Vec::new();
    data.extend_from_slice(keyword.as_bytes());
    // Null separator, not compressed, no language, no translated keyword.
    data.extend_from_slice(&[0, 0, 0, 0, 0]);
    data.extend_from_slice(text.as_bytes());
    let mut chunk = Vec::with_capacity(data.len() + 12);
    chunk.extend_from_slice(&(data.len() as u32).to_be_bytes());
    let body: Vec<u8> = b"iTXt".iter().chain(&data).copied().collect();
    chunk.extend_from_slice(&body);
    chunk.extend_from_slice(&crc32(&body).to_be_bytes());
    let at = png.len() - IEND_LEN;
    let mut out = png[..at].to_vec();
    out.extend_from_slice(&chunk);
    out.extend_from_slice(&png[at..]);
    out
}

/// The CRC-32 (ISO-HDLC, as PNG uses) of `bytes`.
fn crc32(bytes: &[u8]) -> u32 {
    let mut c = 0xFFFF_FFFFu32;
    for &b in bytes {
        c ^= u32::from(b);
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A provenance as the CLI makes it, for the tests of this module and of [`pdf`].
    pub(crate) fn provenance() -> Provenance {
        Provenance {
            program: "capstan 0.1.0".into(),
            commit: "0123456789ab".into(),
            input: None,
            input_sha256: None,
            command_line: "capstan analyze".into(),
        }
    }

    #[test]
    fn crc32_of_known_text() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
    }

    #[test]
    fn figures_carry_the_provenance() {
        let p = Provenance {
            input: Some("a<b>.csv".into()),
            input_sha256: Some("00".into()),
            ..provenance()
        };
        let svg = figure("f.svg", b"<svg a=\"1\"><g/></svg>".to_vec(), &p);
        let svg = String::from_utf8(svg).unwrap();
        assert!(
            svg.starts_with("<svg a=\"1\"><metadata id=\"capstan-provenance\">capstan ")
                && svg.contains("a&lt;b&gt;.csv"),
            "{svg}"
        );
        // A minimal PNG: signature, IEND.
        let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
        png.extend_from_slice(&[0, 0, 0, 0]);
        png.extend_from_slice(b"IEND");
        png.extend_from_slice(&crc32(b"IEND").to_be_bytes());
        let out = figure("f.png", png.clone(), &p);
        assert!(out.ends_with(&png[8..]));
        let text = String::from_utf8_lossy(&out);
        assert!(
            text.contains("iTXtComment") && text.contains(&p.commit),
            "{text}"
        );
    }
}
