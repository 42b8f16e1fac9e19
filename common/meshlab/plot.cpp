#include "plot.h"

#include <QFont>
#include <QImage>
#include <QPainter>
#include <QPainterPath>
#include <QString>
#include <algorithm>
#include <cmath>

#include "pectus/errors.h"

namespace pectus::ml {

namespace {
double niceStep(double range, int ticks) {
  const double raw = range / std::max(ticks, 1);
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
    if (m * p >= raw) return m * p;
  return 10 * p;
}
}  // namespace

void writeLinePlot(const std::string& path, const std::string& title, const std::string& xLabel, const std::string& yLabel,
                   const std::vector<PlotSeries>& series, const std::vector<std::pair<double, std::string>>& hlines,
                   int width, int height) {
  double x0 = 0, x1 = 0, y0 = 0, y1 = 0;
  for (const auto& s : series)
    for (const auto& p : s.points) x0 = std::min(x0, p.first), x1 = std::max(x1, p.first), y0 = std::min(y0, p.second), y1 = std::max(y1, p.second);
  for (const auto& h : hlines) y1 = std::max(y1, h.first), y0 = std::min(y0, h.first);
  if (x1 <= x0) x1 = x0 + 1;
  if (y1 <= y0) y1 = y0 + 1;
  const double xs = niceStep(x1 - x0, 8), ys = niceStep(y1 - y0, 8);
  x1 = std::ceil(x1 / xs) * xs, y1 = std::ceil(y1 / ys) * ys;
  x0 = std::floor(x0 / xs) * xs, y0 = std::floor(y0 / ys) * ys;

  QImage img(width, height, QImage::Format_ARGB32);
  img.fill(Qt::white);
  QPainter g(&img);
  g.setRenderHint(QPainter::Antialiasing);
  const int L = 80, R = 30, T = 50, B = 60;
  const QRectF area(L, T, width - L - R, height - T - B);
  auto X = [&](double x) { return area.left() + (x - x0) / (x1 - x0) * area.width(); };
  auto Y = [&](double y) { return area.bottom() - (y - y0) / (y1 - y0) * area.height(); };
  QFont f = g.font();
  f.setPixelSize(14);
  g.setFont(f);
  g.setPen(QColor(220, 220, 220));
  for (double x = x0; x <= x1 + 1e-9 * xs; x += xs) g.drawLine(QPointF(X(x), area.top()), QPointF(X(x), area.bottom()));
  for (double y = y0; y <= y1 + 1e-9 * ys; y += ys) g.drawLine(QPointF(area.left(), Y(y)), QPointF(area.right(), Y(y)));
  g.setPen(Qt::black);
  g.drawRect(area);
  for (double x = x0; x <= x1 + 1e-9 * xs; x += xs)
    g.drawText(QRectF(X(x) - 40, area.bottom() + 4, 80, 20), Qt::AlignHCenter | Qt::AlignTop, QString::number(x, 'g', 5));
  for (double y = y0; y <= y1 + 1e-9 * ys; y += ys)
    g.drawText(QRectF(0, Y(y) - 10, L - 6, 20), Qt::AlignRight | Qt::AlignVCenter, QString::number(y, 'g', 5));
  g.drawText(QRectF(L, height - 28, area.width(), 24), Qt::AlignHCenter, QString::fromStdString(xLabel));
  g.save();
  g.translate(18, area.center().y());
  g.rotate(-90);
  g.drawText(QRectF(-area.height() / 2, -12, area.height(), 24), Qt::AlignHCenter, QString::fromStdString(yLabel));
  g.restore();
  QFont tf = f;
  tf.setPixelSize(17);
  tf.setBold(true);
  g.setFont(tf);
  g.drawText(QRectF(0, 10, width, 30), Qt::AlignHCenter, QString::fromStdString(title));
  g.setFont(f);
  for (const auto& h : hlines) {
    g.setPen(QPen(QColor(200, 60, 60), 1.5, Qt::DashLine));
    g.drawLine(QPointF(area.left(), Y(h.first)), QPointF(area.right(), Y(h.first)));
    g.drawText(QPointF(area.left() + 8, Y(h.first) - 6), QString::fromStdString(h.second));
  }
  int legendY = T + 12;
  for (const auto& s : series) {
    const QColor c((s.rgb >> 16) & 255, (s.rgb >> 8) & 255, s.rgb & 255);
    g.setPen(QPen(c, 2.2));
    QPainterPath path;
    for (size_t i = 0; i < s.points.size(); ++i) {
      const QPointF q(X(s.points[i].first), Y(s.points[i].second));
      if (i == 0) path.moveTo(q);
      else path.lineTo(q);
    }
    g.drawPath(path);
    if (s.markers) {
      g.setBrush(c);
      for (const auto& p : s.points) g.drawEllipse(QPointF(X(p.first), Y(p.second)), 3.5, 3.5);
      g.setBrush(Qt::NoBrush);
    }
    if (!s.label.empty()) {
      g.drawLine(QPointF(area.left() + 14, legendY), QPointF(area.left() + 40, legendY));
      g.setPen(Qt::black);
      g.drawText(QPointF(area.left() + 48, legendY + 5), QString::fromStdString(s.label));
      legendY += 22;
    }
  }
  g.end();
  if (!img.save(QString::fromStdString(path), "PNG")) throw InputError("Cannot write the plot '" + path + "'.");
}

}  // namespace pectus::ml
