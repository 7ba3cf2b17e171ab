"""confront.experiments"""
