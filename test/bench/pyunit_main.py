"""Runs a unittest TestCase as a catkin test: verbose to stdout, JUnit XML for catkin_test_results
with --xunit RESULTS.xml, exit status 1 on any failure or error."""
import os
import sys
import time
import unittest
import xml.etree.ElementTree as ET


def xunit(case_class, result, seconds, path):
    """JUnit XML of one TestCase's run."""
    tests = unittest.defaultTestLoader.loadTestsFromTestCase(case_class)
    name = os.path.splitext(os.path.basename(sys.argv[0]))[0]
    suite = ET.Element('testsuite', name=name, tests=str(tests.countTestCases()), errors=str(len(result.errors)),
                       failures=str(len(result.failures)), skipped=str(len(result.skipped)), time='%.3f' % seconds)
    bad = {t.id(): ('error', m) for t, m in result.errors}
    bad.update({t.id(): ('failure', m) for t, m in result.failures})
    bad.update({t.id(): ('skipped', m) for t, m in result.skipped})
    for test in tests:
        case = ET.SubElement(suite, 'testcase', classname=case_class.__name__, name=test.id().rsplit('.', 1)[1],
                             time='0')
        if test.id() in bad:
            kind, message = bad[test.id()]
            ET.SubElement(case, kind, message=message.strip().split('\n')[-1]).text = message
    ET.ElementTree(suite).write(path, encoding='utf-8', xml_declaration=True)


def main(case_class):
    path = sys.argv[sys.argv.index('--xunit') + 1] if '--xunit' in sys.argv else None
    suite = unittest.defaultTestLoader.loadTestsFromTestCase(case_class)
    start = time.time()
    result = unittest.TextTestRunner(verbosity=2).run(suite)
    if path:
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        xunit(case_class, result, time.time() - start, path)
    sys.exit(0 if result.wasSuccessful() else 1)
