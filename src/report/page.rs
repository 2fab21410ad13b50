//! The page itself: one self-contained HTML file (styles and plots inline,
//! nothing fetched), built section by section.
//!
//! A few lines of script at the end count the plots the browser drew (those
//! with a size on screen) and write the count in the page's footer, where a
//! reader, or the browser test, sees it; the body's `data-plots`,
//! `data-drawn` and `data-loaded-ms` (from navigation to the end of
//! loading) say the same to a program.

use std::fmt::Write as _;

/// Escapes text for HTML.
pub fn esc(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out += "&amp;",
            '<' => out += "&lt;",
            '>' => out += "&gt;",
            '"' => out += "&quot;",
            '\'' => out += "&#39;",
            c => out.push(c),
        }
    }
    out
}

/// Text as inline code.
pub fn code(s: &str) -> String {
    format!("<code>{}</code>", esc(s))
}

/// A table cell: its HTML and an optional class (`ok`, `fail`, `num`).
#[derive(Clone, Debug, Default)]
pub struct Cell {
    /// The cell's content, already HTML.
    pub html: String,
    /// Its class, if any.
    pub class: Option<&'static str>,
}

impl Cell {
    /// A cell of plain text.
    pub fn text(s: &str) -> Self {
        Self {
            html: esc(s),
            class: None,
        }
    }

    /// A number, right-aligned.
    pub fn num(s: &str) -> Self {
        Self {
            html: esc(s),
            class: Some("num"),
        }
    }

    /// A verdict, green when it is `ok`, red when it failed.
    pub fn verdict(s: &str) -> Self {
        let class = if s == "ok" || s == "no bounds" {
            "ok"
        } else if s.starts_with("FAIL") || s.starts_with("FAILED") {
            "fail"
        } else {
            "warn"
        };
        Self {
            html: esc(s),
            class: Some(class),
        }
    }

    /// A link to a file beside the page.
    pub fn link(href: &str, text: &str) -> Self {
        Self {
            html: format!("<a href=\"{}\">{}</a>", esc(href), esc(text)),
            class: None,
        }
    }
}

/// A page being written.
#[derive(Debug, Default)]
pub struct Page {
    title: String,
    body: String,
}

impl Page {
    /// A page titled `title`, which is also its first heading.
    pub fn new(title: &str) -> Self {
        Self {
            title: title.into(),
            body: format!("<h1>{}</h1>\n", esc(title)),
        }
    }

    /// A note under the title, in a coloured box (`partial`, a failure).
    pub fn banner(&mut self, html: &str) {
        let _ = writeln!(self.body, "<p class=\"banner\">{html}</p>");
    }

    /// A section heading, with an id to link to.
    pub fn section(&mut self, id: &str, title: &str) {
        let _ = writeln!(self.body, "<h2 id=\"{}\">{}</h2>", esc(id), esc(title));
    }

    /// A paragraph of HTML.
    pub fn paragraph(&mut self, html: &str) {
        let _ = writeln!(self.body, "<p>{html}</p>");
    }

    /// Definitions: a term and its HTML each.
    pub fn facts(&mut self, facts: &[(&str, String)]) {
        self.body += "<dl>\n";
        for (term, html) in facts {
            let _ = writeln!(self.body, "<dt>{}</dt><dd>{html}</dd>", esc(term));
        }
        self.body += "</dl>\n";
    }

    /// Plots side by side, each an SVG with a caption under it.
    pub fn plots(&mut self, plots: &[(String, String)]) {
        if plots.is_empty() {
            return;
        }
        self.body += "<div class=\"plots\">\n";
        for (svg, caption) in plots {
            let _ = writeln!(
                self.body,
                "<figure class=\"plot\">{svg}<figcaption>{caption}</figcaption></figure>"
            );
        }
        self.body += "</div>\n";
    }

    /// A table; with `fold`, closed under a summary line the reader opens.
    pub fn table(&mut self, header: &[String], rows: &[Vec<Cell>], fold: Option<&str>) {
        if let Some(summary) = fold {
            let _ = writeln!(self.body, "<details><summary>{}</summary>", esc(summary));
        }
        self.body += "<div class=\"scroll\"><table>\n<thead><tr>";
        for h in header {
            let _ = write!(self.body, "<th>{}</th>", esc(h));
        }
        self.body += "</tr></thead>\n<tbody>\n";
        for row in rows {
            self.body += "<tr>";
            for c in row {
                match c.class {
                    Some(class) => {
                        let _ = write!(self.body, "<td class=\"{class}\">{}</td>", c.html);
                    }
                    None => {
                        let _ = write!(self.body, "<td>{}</td>", c.html);
                    }
                }
            }
            self.body += "</tr>\n";
        }
        self.body += "</tbody></table></div>\n";
        if fold.is_some() {
            self.body += "</details>\n";
        }
    }

    /// Preformatted text (a command, a terminal report).
    pub fn pre(&mut self, text: &str) {
        let _ = writeln!(self.body, "<pre>{}</pre>", esc(text));
    }

    /// The whole page.
    pub fn finish(self) -> String {
        format!(
            "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
             <meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n\
             <title>{}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n{}\
             <footer><span id=\"status\">plots not counted (the page's script did not run)</span> · \
             written by weft {}</footer>\n<script>{SCRIPT}</script>\n</body>\n</html>\n",
            esc(&self.title),
            self.body,
            esc(env!("CARGO_PKG_VERSION")),
        )
    }
}

const STYLE: &str = "
body { font-family: system-ui, sans-serif; margin: 1.5rem auto; max-width: 1220px; padding: 0 1rem; color: #222; }
h1 { font-size: 1.6rem; margin-bottom: .3rem; }
h2 { font-size: 1.25rem; margin-top: 2rem; border-bottom: 1px solid #ddd; padding-bottom: .2rem; }
code, pre { font-family: ui-monospace, monospace; font-size: .9em; }
pre { background: #f6f6f6; padding: .6rem .8rem; overflow-x: auto; }
dl { display: grid; grid-template-columns: max-content auto; gap: .2rem 1rem; }
dt { font-weight: 600; }
dd { margin: 0; }
.banner { background: #fff4d6; border-left: 4px solid #e0a800; padding: .5rem .8rem; }
.plots { display: flex; flex-wrap: wrap; gap: .8rem; }
figure.plot { margin: 0; width: 560px; }
figure.plot svg { display: block; width: 560px; height: 340px; }
figcaption { font-size: .85rem; color: #555; padding: .2rem .4rem; }
.legend { display: block; margin-bottom: .2rem; color: #222; }
.key { white-space: nowrap; margin-right: .8rem; }
.key i { display: inline-block; width: 1.1em; height: .35em; margin-right: .3em; vertical-align: middle; }
.scroll { overflow-x: auto; }
table { border-collapse: collapse; font-size: .85rem; margin: .4rem 0; }
th, td { border: 1px solid #ddd; padding: .2rem .5rem; text-align: left; white-space: nowrap; }
th { background: #f3f3f3; position: sticky; top: 0; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
td.ok { color: #1a7f37; }
td.fail { color: #c62828; font-weight: 600; }
td.warn { color: #9a6700; }
details summary { cursor: pointer; margin: .4rem 0; }
footer { margin-top: 2.5rem; font-size: .8rem; color: #777; }
";

const SCRIPT: &str = "
addEventListener('load', () => {
  const plots = [...document.querySelectorAll('figure.plot svg')];
  const drawn = plots.filter(s => { const r = s.getBoundingClientRect(); return r.width > 0 && r.height > 0; });
  document.getElementById('status').textContent = drawn.length + ' of ' + plots.length + ' plots drawn';
  document.body.dataset.plots = plots.length;
  document.body.dataset.drawn = drawn.length;
  document.body.dataset.loadedMs = Math.round(performance.now());
});
";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_escaped_everywhere() {
        let mut p = Page::new("a <b> & c");
        p.table(
            &["k<".into()],
            &[vec![Cell::text("x\"y"), Cell::verdict("FAIL (1)")]],
            None,
        );
        let html = p.finish();
        assert!(html.contains("<title>a &lt;b&gt; &amp; c</title>"));
        assert!(html.contains("<th>k&lt;</th>"));
        assert!(html.contains("<td>x&quot;y</td><td class=\"fail\">FAIL (1)</td>"));
    }
}
