// What the browser tests share: their command line, and Debian's chromium started
// headless by puppeteer-core with the flags this closed network needs (no background
// connections, no component updates) and a fresh profile, which close() removes.
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import puppeteer from 'puppeteer-core';

// --name value pairs of the command line as an object.
export function parseArgs(argv) {
  return Object.fromEntries(
    argv.reduce((pairs, a, i, all) => (a.startsWith('--') ? [...pairs, [a.slice(2), all[i + 1]]] : pairs), []));
}

// { browser, page, pageErrors, close() }: a page of the given size whose script errors
// are collected in pageErrors.
export async function openPage(width, height) {
  const chromium = process.env.FINDMUG_CHROMIUM || '/usr/bin/chromium';
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), 'findmug-chromium-'));
  const browser = await puppeteer.launch({
    executablePath: chromium,
    headless: true,
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
           '--disable-background-networking', '--disable-component-update', '--disable-sync',
           `--user-data-dir=${profile}`, `--window-size=${width},${height}`],
  });
  const close = async () => {
    await browser.close();
    fs.rmSync(profile, { recursive: true, force: true });
  };
  try {
    const page = await browser.newPage();
    await page.setViewport({ width, height });
    const pageErrors = [];
    page.on('pageerror', (e) => pageErrors.push(String(e)));
    return { browser, page, pageErrors, close };
  } catch (e) {
    await close();
    throw e;
  }
}
