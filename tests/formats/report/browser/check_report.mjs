// Opens one of hil's HTML reports in Debian's headless Chromium (driven by playwright-core; no
// browser is downloaded) and checks what a reader sees, as the reader's browser renders it:
//   - the verdict block is on the first screen (1400 x 900) and says something;
//   - nothing overflows horizontally, at 1400 px and at 900 px wide (no line cut at the edge);
//   - every figure is drawn (an SVG with content, at a readable size), at least `min_figures`;
//   - every link works (in-page anchors exist; downloads are data: URLs; nothing else);
//   - no console error, no page error, no request leaves the file (self-contained);
//   - each text in `expect` is on the page;
//   - it prints to PDF (Chromium's print).
// Writes KIND.png (first screen), KIND-full.png and KIND.pdf into OUT. Exit 1 with every failure
// listed, 2 on a usage error.
//
// usage: node check_report.mjs CHROMIUM OUT KIND REPORT.html MIN_FIGURES [EXPECTED TEXT | fig:FIGURE TITLE ...]
import { chromium } from 'playwright-core';
import { pathToFileURL } from 'node:url';
import { mkdirSync, statSync } from 'node:fs';
import { join } from 'node:path';

const [exe, out, kind, report, minFiguresText, ...expect] = process.argv.slice(2);
if (!exe || !out || !kind || !report || !minFiguresText) {
  console.error('usage: node check_report.mjs CHROMIUM OUT KIND REPORT.html MIN_FIGURES [EXPECTED TEXT ...]');
  process.exit(2);
}
const minFigures = Number(minFiguresText);
mkdirSync(out, { recursive: true });
const failures = [];
const fail = (what) => failures.push(what);

const browser = await chromium.launch({ executablePath: exe, args: ['--disable-gpu'] });
try {
  const page = await browser.newPage({ viewport: { width: 1400, height: 900 } });
  page.on('console', (m) => { if (m.type() === 'error' || m.type() === 'warning') fail(`console ${m.type()}: ${m.text()}`); });
  page.on('pageerror', (e) => fail(`page error: ${e.message}`));
  page.on('requestfailed', (r) => fail(`request failed: ${r.url()}`));
  page.on('request', (r) => {
    const u = r.url();
    if (!u.startsWith('file:') && !u.startsWith('data:')) fail(`request leaves the page: ${u}`);
  });
  await page.goto(pathToFileURL(report).href, { waitUntil: 'load' });

  // The verdict, first.
  const verdict = await page.evaluate(() => {
    const v = document.querySelector('#verdict');
    if (!v) return null;
    const b = v.getBoundingClientRect();
    const h = v.querySelector('.headline');
    return { top: b.top, bottom: b.bottom, headline: h ? h.textContent.trim() : '', text: v.textContent };
  });
  if (!verdict) fail('no verdict block (#verdict)');
  else {
    if (verdict.top < 0 || verdict.bottom > 900) fail(`the verdict is not on the first screen (${verdict.top}..${verdict.bottom} px of 900)`);
    if (verdict.headline.length < 10) fail(`the verdict's headline says nothing: "${verdict.headline}"`);
  }

  // Horizontal overflow: the page, and any element whose content is cut or scrolled sideways.
  const overflow = async (width) => {
    await page.setViewportSize({ width, height: 900 });
    return page.evaluate(() => {
      const found = [];
      const d = document.documentElement;
      if (d.scrollWidth > d.clientWidth + 1) found.push(`the page is ${d.scrollWidth} px wide in a ${d.clientWidth} px window`);
      for (const e of document.querySelectorAll('body *')) {
        const cs = getComputedStyle(e);
        if (cs.overflowX !== 'visible' && e.scrollWidth > e.clientWidth + 1)
          found.push(`<${e.tagName.toLowerCase()} class="${e.className.baseVal ?? e.className}"> scrolls sideways (${e.scrollWidth} > ${e.clientWidth} px)`);
        const b = e.getBoundingClientRect();
        if (b.width > 0 && b.right > d.clientWidth + 1 && cs.position !== 'fixed' && !e.closest('svg'))
          found.push(`<${e.tagName.toLowerCase()}> ends at ${Math.round(b.right)} px, past the window's ${d.clientWidth}`);
      }
      // Text cut at its figure's edge (an SVG clips what it does not hold).
      for (const t of document.querySelectorAll('svg text')) {
        const b = t.getBoundingClientRect(), f = t.ownerSVGElement.getBoundingClientRect();
        if (b.width > 0 && (b.right > f.right + 1 || b.left < f.left - 1))
          found.push(`figure text "${t.textContent.slice(0, 40)}" is cut at its figure's edge`);
      }
      return [...new Set(found)].slice(0, 10);
    });
  };
  for (const w of [1400, 900]) for (const o of await overflow(w)) fail(`at ${w} px: ${o}`);
  await page.setViewportSize({ width: 1400, height: 900 });

  // Figures.
  const figs = await page.evaluate(() => [...document.querySelectorAll('figure.fig')].map((f) => {
    const s = f.querySelector('svg');
    if (!s) return { id: f.id, svg: false };
    const b = s.getBoundingClientRect();
    return { id: f.id, svg: true, width: b.width, height: b.height, marks: s.querySelectorAll('path,circle,rect,line').length,
             title: (s.querySelector('text') || {}).textContent || '' };
  }));
  if (figs.length < minFigures) fail(`${figs.length} figures, expected at least ${minFigures}`);
  for (const f of figs) {
    if (!f.svg) fail(`figure ${f.id} has no SVG`);
    else if (f.width < 300 || f.height < 80) fail(`figure ${f.id} (${f.title}) is drawn ${Math.round(f.width)} x ${Math.round(f.height)} px`);
    else if (f.marks < 3) fail(`figure ${f.id} (${f.title}) is empty`);
  }

  // Links.
  const links = await page.evaluate(() => [...document.querySelectorAll('a[href]')].map((a) => {
    const h = a.getAttribute('href');
    return { href: h.slice(0, 60), ok: h.startsWith('#') ? !!document.getElementById(decodeURIComponent(h.slice(1))) : h.startsWith('data:') };
  }));
  for (const l of links) if (!l.ok) fail(`broken link: ${l.href}`);
  if (!links.some((l) => l.href.startsWith('#'))) fail('no table of contents (no in-page link)');

  // The texts a reader of this kind must find.
  // (fig:TITLE: a figure whose title holds TITLE.)
  const body = await page.evaluate(() => document.body.innerText);
  for (const t of expect) {
    if (t.startsWith('fig:')) {
      if (!figs.some((f) => f.title.includes(t.slice(4)))) fail(`missing figure: "${t.slice(4)}"`);
    } else if (!body.includes(t)) fail(`missing text: "${t}"`);
  }

  await page.screenshot({ path: join(out, `${kind}.png`) });
  await page.screenshot({ path: join(out, `${kind}-full.png`), fullPage: true });
  const pdf = join(out, `${kind}.pdf`);
  await page.pdf({ path: pdf, format: 'A4', printBackground: true });
  if (statSync(pdf).size < 10000) fail(`the printed PDF is only ${statSync(pdf).size} bytes`);
  console.log(`${kind}: ${figs.length} figures, ${links.length} links, verdict "${verdict ? verdict.headline.slice(0, 90) : ''}"`);
} finally {
  await browser.close();
}
if (failures.length) {
  for (const f of failures) console.error(`${kind}: FAIL ${f}`);
  process.exit(1);
}
