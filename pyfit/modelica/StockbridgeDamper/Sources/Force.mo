within StockbridgeDamper.Sources;
model Force "Force source: applies the input force u to the flange"
  input Real u(unit="N") "Force applied to the flange, positive in +s direction";
  Interfaces.Flange flange "Flange the force acts on";
equation
  flange.f = -u;
end Force;
