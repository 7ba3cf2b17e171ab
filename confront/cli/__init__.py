"""confront.cli"""
