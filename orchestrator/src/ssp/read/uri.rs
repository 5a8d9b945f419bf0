//! URIs in an SSP description (`source`): relative references and `file:` URIs, resolved to
//! absolute paths, confined to the archive when read from one.

use std::path::PathBuf;

use model_description::xml::Element;

use super::super::error::SspError;
use super::Reader;
use super::files::normalize;

impl Reader<'_> {
    /// Resolves a URI attribute (relative reference or `file:` URI) to an absolute path.
    pub(super) fn resolve(
        &self,
        e: &Element,
        attribute: &'static str,
        uri: &str,
        context: &str,
    ) -> Result<PathBuf, SspError> {
        let offset = e.attribute(attribute).map_or(e.offset, |a| a.offset);
        let fail = |reason: String| {
            let (line, column) = self.at(offset);
            SspError::Invalid {
                line,
                column,
                message: format!(
                    "{attribute}=\"{uri}\" of <{}> ({context}): {reason}",
                    e.name
                ),
            }
        };
        if uri.is_empty() {
            return Err(fail("an empty URI".into()));
        }
        if uri.contains('#') {
            return Err(self.unsupported(offset, format!("{attribute}=\"{uri}\" of {context}: a URI with a fragment (a system inside another SSD or SSP)")));
        }
        let path = if let Some(rest) = uri.strip_prefix("file:") {
            let path = match rest.strip_prefix("//") {
                Some(after) => {
                    let slash = after
                        .find('/')
                        .ok_or_else(|| fail("a file: URI without a path".into()))?;
                    let host = &after[..slash];
                    if !host.is_empty() && !host.eq_ignore_ascii_case("localhost") {
                        return Err(fail(format!("a file: URI on another host ('{host}')")));
                    }
                    &after[slash..]
                }
                None => rest,
            };
            let path = PathBuf::from(
                percent_decode(path).ok_or_else(|| fail("bad percent-encoding".into()))?,
            );
            if !path.is_absolute() {
                return Err(fail("a relative file: URI".into()));
            }
            path
        } else {
            if let Some(colon) = uri.find(':') {
                let scheme = &uri[..colon];
                let is_scheme = scheme.len() > 1
                    && scheme.starts_with(|c: char| c.is_ascii_alphabetic())
                    && scheme
                        .chars()
                        .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c));
                if is_scheme {
                    return Err(self.unsupported(offset, format!("{attribute}=\"{uri}\" of {context}: the URI scheme '{scheme}:' (relative references and file: URIs are)")));
                }
            }
            let decoded = percent_decode(uri).ok_or_else(|| fail("bad percent-encoding".into()))?;
            self.place.base_dir.join(decoded)
        };
        let path = normalize(&path);
        if self.place.confine && !path.starts_with(&self.place.base_dir) {
            return Err(fail("it points outside the .ssp archive".into()));
        }
        Ok(path)
    }
}

fn percent_decode(text: &str) -> Option<String> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = text.get(i + 1..i + 3)?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b/%C3%A9").as_deref(), Some("a b/é"));
        assert_eq!(percent_decode("a%2"), None);
    }
}
