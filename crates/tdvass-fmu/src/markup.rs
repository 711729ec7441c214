//! What the generated model descriptions and documentation pages of every
//! FMI version write alike: the one-line model description, numbers,
//! elements with text, paragraphs, lists, tables and the HTML page around
//! a body (quick-xml, never written by hand).

use quick_xml::Writer;
use quick_xml::events::{BytesText, Event};
use std::io::Cursor;

/// A writer of XML (or HTML) into memory.
pub type XmlWriter = Writer<Cursor<Vec<u8>>>;
/// What writing into memory returns.
pub type XmlResult = std::io::Result<()>;

/// One-line description of the model.
pub const MODEL_DESCRIPTION: &str = "Quarter-car suspension with an annular vibration-absorbing structure and time-delay feedback of the tire displacement (TDVASS), with the conventional (CS) and uncontrolled absorber (PVASS) suspensions for comparison";

/// The style sheet of the documentation pages.
const STYLE: &str = "body{font-family:sans-serif;max-width:70em;margin:auto;padding:1em}table{border-collapse:collapse}td,th{border:1px solid #bbb;padding:0.2em 0.5em;text-align:left;vertical-align:top}";

/// What the documentation says of the reference results every FMU carries
/// (fmu-build writes them and checks that this paragraph names their file
/// and interval).
pub const REFERENCE_RESULTS: &str = "Reference results (the layered standard FMI-LS-REF): extra/org.fmi-standard.fmi-ls-ref/tdvass_out.csv, named by fmi-ls-manifest.xml beside it, holds every Real output of the default experiment every 0.05 s (time in the first column), computed when the FMU was built by the same slave its binaries wrap. A master that runs the default experiment with communication steps of 0.05 s reproduces every column to within 1e-12 of its largest absolute value.";

/// Short number formatting: Rust's shortest round-trip representation.
pub fn number(v: f64) -> String {
    format!("{v}")
}

/// A writer indenting by two spaces.
pub fn writer() -> XmlWriter {
    Writer::new_with_indent(Cursor::new(Vec::new()), b' ', 2)
}

/// The text written, with a final newline.
pub fn finish(w: XmlWriter) -> String {
    let mut text = String::from_utf8(w.into_inner().into_inner()).expect("quick-xml writes UTF-8");
    text.push('\n');
    text
}

/// `<name>text</name>`, the text escaped.
pub fn text_element(w: &mut XmlWriter, name: &str, text: &str) -> XmlResult {
    w.create_element(name)
        .write_text_content(BytesText::new(text))?;
    Ok(())
}

/// `<p>text</p>`.
pub fn paragraph(w: &mut XmlWriter, text: &str) -> XmlResult {
    text_element(w, "p", text)
}

/// A `<ul>` of `items`.
pub fn list(w: &mut XmlWriter, items: &[&str]) -> XmlResult {
    w.create_element("ul").write_inner_content(|w| {
        for item in items {
            text_element(w, "li", item)?;
        }
        Ok(())
    })?;
    Ok(())
}

/// A `<table>` with a header row and `rows`.
pub fn table(w: &mut XmlWriter, header: &[&str], rows: &[Vec<String>]) -> XmlResult {
    w.create_element("table").write_inner_content(|w| {
        w.create_element("tr").write_inner_content(|w| {
            for h in header {
                text_element(w, "th", h)?;
            }
            Ok(())
        })?;
        for row in rows {
            w.create_element("tr").write_inner_content(|w| {
                for cell in row {
                    text_element(w, "td", cell)?;
                }
                Ok(())
            })?;
        }
        Ok(())
    })?;
    Ok(())
}

/// A complete HTML page titled `title` whose body `write_body` writes.
pub fn html_page(title: &str, write_body: impl Fn(&mut XmlWriter) -> XmlResult) -> String {
    let mut w = writer();
    let write = |w: &mut XmlWriter| -> XmlResult {
        w.write_event(Event::DocType(BytesText::from_escaped("html")))?;
        w.create_element("html")
            .with_attribute(("lang", "en"))
            .write_inner_content(|w| {
                w.create_element("head").write_inner_content(|w| {
                    w.create_element("meta")
                        .with_attribute(("charset", "utf-8"))
                        .write_empty()?;
                    text_element(w, "title", title)?;
                    text_element(w, "style", STYLE)
                })?;
                w.create_element("body").write_inner_content(&write_body)?;
                Ok(())
            })?;
        Ok(())
    };
    write(&mut w).expect("writing to memory cannot fail");
    finish(w)
}
