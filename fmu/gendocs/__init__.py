"""The generated parts of docs/ and the README, and the reader of the FMI state rules they show.

``generated_docs`` writes them (`python -m fmu.gendocs`; tests/test_docs.py checks they are
current); ``fmi_rules`` reads the FMI state tables out of the C layer (fmu/c/).
"""
