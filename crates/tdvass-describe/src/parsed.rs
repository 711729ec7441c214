//! The generated XML read back, for the tests: every element with its
//! attributes and its parent.

use quick_xml::Reader;
use quick_xml::events::Event;
use std::collections::HashMap;

/// One element: its name, its attributes and the index of its parent.
#[derive(Debug)]
pub(crate) struct Element {
    pub(crate) name: String,
    pub(crate) attributes: HashMap<String, String>,
    pub(crate) parent: Option<usize>,
}

impl Element {
    pub(crate) fn get(&self, key: &str) -> Option<&str> {
        self.attributes.get(key).map(String::as_str)
    }

    pub(crate) fn attr(&self, key: &str) -> &str {
        self.get(key)
            .unwrap_or_else(|| panic!("<{}> has no `{key}`: {:?}", self.name, self.attributes))
    }
}

/// Every element in document order.
pub(crate) fn elements(xml: &str) -> Vec<Element> {
    let mut reader = Reader::from_str(xml);
    let mut out: Vec<Element> = Vec::new();
    let mut open: Vec<usize> = Vec::new();
    loop {
        let event = reader.read_event().expect("well-formed XML");
        let (e, empty) = match event {
            Event::Start(e) => (e, false),
            Event::Empty(e) => (e, true),
            Event::End(_) => {
                open.pop();
                continue;
            }
            Event::Eof => break,
            _ => continue,
        };
        let attributes = e
            .attributes()
            .map(|a| {
                let a = a.unwrap();
                (
                    a.key.0.to_string(),
                    a.normalized_value(quick_xml::XmlVersion::Implicit1_0)
                        .unwrap()
                        .into_owned(),
                )
            })
            .collect();
        out.push(Element {
            name: e.name().0.to_string(),
            attributes,
            parent: open.last().copied(),
        });
        if !empty {
            open.push(out.len() - 1);
        }
    }
    out
}
