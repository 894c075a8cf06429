"""
The README's example of the pytest fixture is the very test the suite runs, word for word.

The README shows a whole test file of a user's node; test/world_node/test_readme_example.py is
that file, run by the suite. These checks keep the two from drifting apart, and the README
linked to the fixture's page.
"""

import os
import re

from repository import read_file, ROOT

README = os.path.join(ROOT, 'README.md')
EXAMPLE = os.path.join(ROOT, 'test', 'world_node', 'test_readme_example.py')
FIXTURE_DOCS = os.path.join(ROOT, 'docs', 'testing-with-the-world.md')
SECTION = '## Testing your own nodes\n'


def first_python_block(markdown, heading):
    """Return the first ```python block of a markdown section, or None if it has none."""
    section = markdown.split(heading, 1)[1].split('\n## ', 1)[0]
    found = re.search(r'^```python\n(.*?)^```$', section, re.DOTALL | re.MULTILINE)
    return found.group(1) if found else None


def test_the_block_finder_takes_the_sections_first_python_block_only():
    markdown = ('# Title\n## Other\n```python\nother = 1\n```\n' + SECTION +
                'Text.\n```bash\nls\n```\n```python\nmine = 2\n```\n```python\nlater = 3\n```\n'
                '## Next\n```python\nnext = 4\n```\n')
    assert first_python_block(markdown, SECTION) == 'mine = 2\n'
    assert first_python_block('# Title\n' + SECTION + 'No code.\n## Next\n```python\nx\n```\n',
                              SECTION) is None


def test_the_readme_shows_the_example_the_suite_runs_word_for_word():
    readme = read_file(README)
    assert SECTION in readme, f'the README has no section {SECTION.strip()!r}'
    assert first_python_block(readme, SECTION) == read_file(EXAMPLE), \
        f'the README example differs from {os.path.relpath(EXAMPLE, ROOT)}: copy the file in'


def test_the_example_is_short_and_loads_the_fixture_as_users_do():
    example = read_file(EXAMPLE)
    assert len(example.splitlines()) < 40
    assert "pytest_plugins = ['service_tutorial.testing.fixtures']" in example


def test_the_readme_links_the_fixtures_page_and_its_section():
    readme = read_file(README)
    assert '(docs/testing-with-the-world.md#testing-your-own-nodes-the-pytest-fixture)' in readme
    assert '\n## Testing your own nodes: the pytest fixture\n' in read_file(FIXTURE_DOCS)
