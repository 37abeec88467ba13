//! A well-formedness checker for the XML that `stickslip_cli::figure` writes (test code: the
//! figures themselves are not checked in production; tests/figures.rs and tests/reproduce.rs
//! check every kind of figure written).

use std::collections::BTreeMap;

/// Checks that `xml` is a well-formed XML document of the kind `stickslip_cli::figure::svg::Svg` writes (a prolog,
/// comments, elements with quoted attributes, text with only the predefined or numeric entity
/// references) with a single root element. Returns the number of elements of each name.
pub fn check_well_formed(xml: &str) -> Result<BTreeMap<String, usize>, String> {
    let mut counts = BTreeMap::new();
    let mut stack: Vec<&str> = Vec::new();
    let mut roots = 0;
    let mut rest = xml;
    let offset = |rest: &str| xml.len() - rest.len();
    if let Some(r) = rest.strip_prefix("<?xml") {
        let end = r.find("?>").ok_or("unterminated XML declaration")?;
        rest = &r[end + 2..];
    }
    while !rest.is_empty() {
        if let Some(r) = rest.strip_prefix("<!--") {
            let end = r
                .find("-->")
                .ok_or_else(|| format!("unterminated comment at byte {}", offset(rest)))?;
            rest = &r[end + 3..];
        } else if let Some(r) = rest.strip_prefix("</") {
            let end = r
                .find('>')
                .ok_or_else(|| format!("unterminated end tag at byte {}", offset(rest)))?;
            let name = r[..end].trim_end();
            match stack.pop() {
                Some(open) if open == name => {}
                Some(open) => {
                    return Err(format!("</{name}> at byte {} closes <{open}>", offset(rest)))
                }
                None => return Err(format!("</{name}> at byte {} closes nothing", offset(rest))),
            }
            rest = &r[end + 1..];
        } else if let Some(r) = rest.strip_prefix('<') {
            let name_end = r
                .find(|c: char| c.is_whitespace() || c == '>' || c == '/')
                .ok_or("unterminated start tag")?;
            let name = &r[..name_end];
            if name.is_empty()
                || !name
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == ':' || c == '_')
            {
                return Err(format!("bad element name {name:?} at byte {}", offset(rest)));
            }
            let mut a = &r[name_end..];
            let mut seen = Vec::new();
            let self_closing = loop {
                a = a.trim_start();
                if let Some(t) = a.strip_prefix("/>") {
                    a = t;
                    break true;
                }
                if let Some(t) = a.strip_prefix('>') {
                    a = t;
                    break false;
                }
                let eq =
                    a.find('=').ok_or_else(|| format!("attribute without value in <{name}>"))?;
                let key = a[..eq].trim();
                if key.is_empty()
                    || key.contains(|c: char| c.is_whitespace() || c == '<' || c == '"')
                {
                    return Err(format!("bad attribute name {key:?} in <{name}>"));
                }
                if seen.contains(&key) {
                    return Err(format!("duplicate attribute {key} in <{name}>"));
                }
                seen.push(key);
                let v = a[eq + 1..].trim_start();
                let quote = v
                    .chars()
                    .next()
                    .filter(|&c| c == '"' || c == '\'')
                    .ok_or_else(|| format!("unquoted value of {key} in <{name}>"))?;
                let close = v[1..]
                    .find(quote)
                    .ok_or_else(|| format!("unterminated value of {key} in <{name}>"))?;
                let value = &v[1..1 + close];
                if value.contains('<') {
                    return Err(format!("'<' in the value of {key} in <{name}>"));
                }
                check_entities(value)?;
                a = &v[close + 2..];
            };
            if stack.is_empty() {
                roots += 1;
                if roots > 1 {
                    return Err(format!("a second root element <{name}>"));
                }
            }
            *counts.entry(name.to_string()).or_insert(0) += 1;
            if !self_closing {
                stack.push(name);
            }
            rest = a;
        } else {
            let end = rest.find('<').unwrap_or(rest.len());
            let text = &rest[..end];
            if stack.is_empty() && !text.trim().is_empty() {
                return Err(format!("text outside the root element at byte {}", offset(rest)));
            }
            if text.contains('>') && text.contains("]]>") {
                return Err("']]>' in text".into());
            }
            check_entities(text)?;
            rest = &rest[end..];
        }
    }
    if let Some(open) = stack.last() {
        return Err(format!("<{open}> is never closed"));
    }
    if roots == 0 {
        return Err("no root element".into());
    }
    Ok(counts)
}

fn check_entities(text: &str) -> Result<(), String> {
    let mut rest = text;
    while let Some(i) = rest.find('&') {
        let r = &rest[i + 1..];
        let end = r.find(';').ok_or_else(|| format!("'&' without ';' in {text:?}"))?;
        let name = &r[..end];
        let ok = matches!(name, "amp" | "lt" | "gt" | "quot" | "apos")
            || name
                .strip_prefix("#x")
                .is_some_and(|h| !h.is_empty() && h.chars().all(|c| c.is_ascii_hexdigit()))
            || name
                .strip_prefix('#')
                .is_some_and(|d| !d.is_empty() && d.chars().all(|c| c.is_ascii_digit()));
        if !ok {
            return Err(format!("unknown entity &{name}; in {text:?}"));
        }
        rest = &r[end + 1..];
    }
    Ok(())
}
