#!/usr/bin/env python3
"""Checks every relative link of the Markdown files: each `](target)` must name a file or folder
that exists (a `#fragment` is checked against the target's headings). Usage, from anywhere:
    python3 scripts/check_doc_links.py [--allow PREFIX]...
PREFIX (repeatable) names targets, relative to the repository, that may be missing (for example
docs/reference/, written by a generator). Links into ../shared/ are resolved beside the main
checkout when this is a worktree. Exit status 1 when a link is broken."""
import os, re, subprocess, sys

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
allow = [a for i, a in enumerate(sys.argv[1:]) if i > 0 and sys.argv[i] == '--allow']

def anchors(path):
    out = set()
    in_code = False
    for line in open(path, encoding='utf-8'):
        if line.startswith('```'):
            in_code = not in_code
        if in_code or not line.startswith('#'):
            continue
        title = line.lstrip('#').strip().lower()
        title = re.sub(r'[^\w\- ]', '', title)
        out.add(title.replace(' ', '-'))
    return out

def main_checkout():
    try:
        common = subprocess.run(['git', '-C', root, 'rev-parse', '--git-common-dir'],
                                capture_output=True, text=True, check=True).stdout.strip()
        return os.path.dirname(os.path.abspath(os.path.join(root, common)))
    except Exception:
        return root

files = subprocess.run(['git', '-C', root, 'ls-files', '-co', '--exclude-standard', '*.md'],
                       capture_output=True, text=True, check=True).stdout.split()
main = main_checkout()
broken = checked = 0
for f in files:
    path = os.path.join(root, f)
    text = open(path, encoding='utf-8').read()
    text = re.sub(r'```.*?```', '', text, flags=re.S)       # links inside code blocks are not links
    text = re.sub(r'`[^`\n]*`', '``', text)                 # nor inside inline code
    for m in re.finditer(r'\]\(([^)\s]+)\)', text):
        target = m.group(1)
        if re.match(r'[a-z]+:', target):
            continue
        checked += 1
        rel, _, frag = target.partition('#')
        full = os.path.normpath(os.path.join(os.path.dirname(path), rel)) if rel else path
        repo_rel = os.path.relpath(full, root)
        if repo_rel.startswith('..'):
            full = os.path.normpath(os.path.join(main, repo_rel))
        if any(repo_rel.startswith(a) for a in allow):
            continue
        if not os.path.exists(full):
            print(f'{f}: {target}: no such file'); broken += 1
        elif frag and full.endswith('.md') and frag not in anchors(full):
            print(f'{f}: {target}: no heading #{frag}'); broken += 1
print(f'{checked} links in {len(files)} files, {broken} broken')
sys.exit(1 if broken else 0)
