"""confront.learning"""
